// The whole training loss of one ray, as the trainer combines the terms of losses.h, written once
// for the CPU trainer and the CUDA loss kernel: EndoNeRF's rendered-colour L2, the depth term (L1 or
// Huber, in units of the depth range so lambda_d means the same for every clip), the paper's RGB NLL
// weighted by w_j = T_j alpha_j and the variance regulariser eta sum_j log(1 + var_j).
//
// The NLL's weights are held constant (no gradient into the densities): through w_j the NLL rewards
// opacity at any sample whose colour fits with a confident variance, which pulls surfaces in front
// of the true one (docs/architecture.md). Geometry is learned from the rendered colour and depth.
#pragma once

#include "common/hd.h"
#include "worker/engine/render/volume_renderer.h"
#include "worker/engine/train/losses.h"

namespace endorecon::train {

// Each term's weight, batch normalisation included; a zero scale leaves the term out.
struct RayLossTerms {
  float rgb_l2_scale = 0;
  float depth_scale = 0;  // lambda_d / rays
  float depth_range = 1;  // far - near, clip units
  float huber_delta = 0;  // in units of the depth range; 0: L1
  float nll_scale = 0;
  float nll_beta = 0;  // 0: the paper's NLL; > 0: beta-NLL (losses.h)
  float variance_reg_scale = 0;
  float variance_eps = field::kDefaultVarianceEps;
};

// Returns the ray's loss. Overwrites *grad with its gradient with respect to the rendered colour
// and depth (for CompositeRayBackward) and ADDS the per-sample gradients of the NLL and the
// regulariser to d_mean_rgb (3n) and d_log_var (n), either of which may be null. prior_depth is
// ignored unless depth_scale != 0 (an unknown prior, <= 0, contributes nothing).
template <typename S>
ENDORECON_HD S RayLoss(const render::RayComposite<S>& ray, const S* weights, const S* mean_rgb,
                       const S* log_var, int n, const S* target_rgb, S prior_depth, const RayLossTerms& terms,
                       render::RayCompositeGrad<S>* grad, S* d_mean_rgb, S* d_log_var) {
  *grad = render::RayCompositeGrad<S>{};
  S loss = 0;
  if (terms.rgb_l2_scale != 0) loss += RenderedColorL2(ray.rgb, target_rgb, S(terms.rgb_l2_scale), grad->rgb);
  if (terms.depth_scale != 0) {
    // The loss is scaled back to clip units; the gradient is per unit of depth.
    const S range = S(terms.depth_range), scale = S(terms.depth_scale) / range;
    const S depth = ray.depth / range, prior = prior_depth / range;
    loss +=
        range * (terms.huber_delta > 0 ? DepthHuber(depth, prior, S(terms.huber_delta), scale, &grad->depth)
                                       : DepthL1(depth, prior, scale, &grad->depth));
  }
  if (terms.nll_scale != 0) {
    loss += RgbNll(weights, mean_rgb, log_var, n, target_rgb, S(terms.variance_eps), S(terms.nll_scale),
                   static_cast<S*>(nullptr), d_mean_rgb, d_log_var, S(terms.nll_beta));
  }
  if (terms.variance_reg_scale != 0) {
    loss += VarianceRegularizer(log_var, n, S(terms.variance_eps), S(terms.variance_reg_scale), d_log_var);
  }
  return loss;
}

}  // namespace endorecon::train
