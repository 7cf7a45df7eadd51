// The training losses of one ray (paper §3, "Training Objective"), each returning its value times
// `scale` (the term's weight, e.g. lambda_d or eta, times any batch normalisation) and ADDING the
// same-scaled gradients to the given arrays (callers zero them first; a null pointer skips that
// gradient). Per-sample arrays follow render/volume_renderer.h: weights[n] = T_j alpha_j,
// mean_rgb[3n], log_var[n] (one colour log-variance per sample, shared by the three channels).
//
// The weighted NLL alone can be lowered by making a ray transparent (all w_j -> 0), so the trainer
// keeps RenderedColorL2 beside it, as EndoNeRF's photometric term.
#pragma once

#include <cmath>

#include "common/hd.h"
#include "worker/engine/field/variance.h"

namespace endorecon::train {

// Paper RGB NLL: sum_j w_j (|mu_j - C|^2 / (2 var_j) + log(var_j) / 2), var_j = softplus(l_j) + eps
// (field::VarianceFromLogVar). The paper's 1/2 log var is kept as written, although a 3-channel
// isotropic Gaussian would have 3/2. Gradients: d_weights[j] (feed to CompositeRayBackward),
// d_mean_rgb[3j..3j+2] and d_log_var[j]. Finite for any finite l (including +-80) and any error,
// as long as eps is a normal number of S (the floor keeps var, and so 1/var, bounded).
//
// beta > 0 gives the beta-NLL of Seitzer et al. (ICLR 2022): each sample's term is weighted by
// var_j^beta held constant (no gradient through the weight). The variance still goes to the squared
// error (the NLL's minimiser is unchanged), but the mean's gradient is w (mu - C) var^(beta - 1)
// instead of w (mu - C) / var: at beta = 1 that of a plain squared error, so a confident variance
// no longer multiplies the pull of the mean colours by up to 1 / eps. beta = 0 is the paper's NLL.
// Measured on the demo clip (docs/benchmarks.md): beta = 1 (NLL weight 1) gains ~0.6 dB held-out
// PSNR and halves the depth error but ranks errors worse (Spearman 0.43 against 0.57); rescaling
// only the mean's gradient, with the paper's variance gradient at a weight that size, wrecks the
// fit (28.9 dB): the variance and the mean share the colour head's hidden layer.
template <typename S>
ENDORECON_HD S RgbNll(const S* weights, const S* mean_rgb, const S* log_var, int n, const S* target_rgb,
                      S eps, S scale, S* d_weights, S* d_mean_rgb, S* d_log_var, S beta = S(0)) {
  S loss = 0;
  for (int j = 0; j < n; ++j) {
    const S var = field::VarianceFromLogVar(log_var[j], eps);
    const S inv_var = S(1) / var;
    const S* mu = mean_rgb + 3 * j;
    const S r0 = mu[0] - target_rgb[0], r1 = mu[1] - target_rgb[1], r2 = mu[2] - target_rgb[2];
    const S error = r0 * r0 + r1 * r1 + r2 * r2;
    const S term = S(0.5) * (error * inv_var + std::log(var));
    const S factor = beta == S(0) ? S(1) : std::pow(var, beta);
    const S w = weights[j] * factor;
    loss += w * term;
    if (d_weights != nullptr) d_weights[j] += scale * term * factor;
    if (d_mean_rgb != nullptr) {
      const S k = scale * w * inv_var;
      d_mean_rgb[3 * j] += k * r0;
      d_mean_rgb[3 * j + 1] += k * r1;
      d_mean_rgb[3 * j + 2] += k * r2;
    }
    if (d_log_var != nullptr) {
      // d term / d var = (1 - error / var) / (2 var), written so no var^2 can underflow.
      const S d_var = S(0.5) * inv_var * (S(1) - error * inv_var);
      d_log_var[j] += scale * w * d_var * field::VarianceFromLogVarGrad(log_var[j]);
    }
  }
  return scale * loss;
}

// |C^ - C|^2 over the three channels of the rendered colour; gradient d_rendered_rgb[0..3).
template <typename S>
ENDORECON_HD S RenderedColorL2(const S* rendered_rgb, const S* target_rgb, S scale, S* d_rendered_rgb) {
  S loss = 0;
  for (int c = 0; c < 3; ++c) {
    const S r = rendered_rgb[c] - target_rgb[c];
    loss += r * r;
    if (d_rendered_rgb != nullptr) d_rendered_rgb[c] += scale * S(2) * r;
  }
  return scale * loss;
}

// True where a prior depth is a measurement: depth maps store 0 (or nothing usable) where unknown.
template <typename S>
ENDORECON_HD bool HasDepthPrior(S prior_depth) {
  return prior_depth > 0 && std::isfinite(prior_depth);
}

// |D^ - D_prior| on the rendered depth; 0 with no gradient where the prior is unknown. The
// gradient at D^ = D_prior is 0.
template <typename S>
ENDORECON_HD S DepthL1(S rendered_depth, S prior_depth, S scale, S* d_rendered_depth) {
  if (!HasDepthPrior(prior_depth)) return S(0);
  const S r = rendered_depth - prior_depth;
  if (d_rendered_depth != nullptr) *d_rendered_depth += scale * (r > 0 ? S(1) : (r < 0 ? S(-1) : S(0)));
  return scale * std::fabs(r);
}

// Huber on the rendered depth with threshold delta > 0: r^2 / 2 for |r| <= delta, else
// delta (|r| - delta / 2); 0 with no gradient where the prior is unknown.
template <typename S>
ENDORECON_HD S DepthHuber(S rendered_depth, S prior_depth, S delta, S scale, S* d_rendered_depth) {
  if (!HasDepthPrior(prior_depth)) return S(0);
  const S r = rendered_depth - prior_depth;
  const S a = std::fabs(r);
  if (a <= delta) {
    if (d_rendered_depth != nullptr) *d_rendered_depth += scale * r;
    return scale * S(0.5) * r * r;
  }
  if (d_rendered_depth != nullptr) *d_rendered_depth += scale * (r > 0 ? delta : -delta);
  return scale * delta * (a - S(0.5) * delta);
}

// Variance regulariser sum_j log(1 + var_j), var_j = softplus(l_j) + eps; gradient d_log_var[j].
template <typename S>
ENDORECON_HD S VarianceRegularizer(const S* log_var, int n, S eps, S scale, S* d_log_var) {
  S loss = 0;
  for (int j = 0; j < n; ++j) {
    const S var = field::VarianceFromLogVar(log_var[j], eps);
    loss += std::log1p(var);
    if (d_log_var != nullptr)
      d_log_var[j] += scale * field::VarianceFromLogVarGrad(log_var[j]) / (S(1) + var);
  }
  return scale * loss;
}

}  // namespace endorecon::train
