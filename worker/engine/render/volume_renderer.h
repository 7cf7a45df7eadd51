// Volume rendering of one ray (paper §3): alpha_j = 1 - exp(-sigma_j delta_j),
// T_j = exp(-sum_{k<j} sigma_k delta_k), w_j = T_j alpha_j, colour C = sum_j w_j c_j,
// depth D = sum_j w_j s_j, opacity A = sum_j w_j; and its exact backward pass in O(n).
//
// Conventions: sigma[n] densities, rgb[3n] colours (sample j at rgb[3j..3j+2]), s[n] ascending
// positions and delta[n] interval lengths (ray_samples.h). Densities < 0 count as 0, as do
// intervals <= 0. The optical depth sigma_j delta_j of one sample is clamped to kMaxOpticalDepth
// (past which alpha is 1 and exp(-tau) is 0 in double anyway), so densities up to float's maximum
// and infinite intervals give finite results; the clamp's gradient is 0. NaN inputs propagate.
//
// A background colour seen through what the samples leave: AddBackground and BackgroundBackward.
//
// Depth is the unnormalised sum_j w_j s_j (EndoNeRF's convention): a ray that hits nothing reports
// depth 0 and a partly transparent ray a depth pulled towards 0. Divide by the opacity (where it
// is > 0) for the expected depth of the termination point.
#pragma once

#include <cmath>

#include "common/hd.h"

namespace endorecon::render {

inline constexpr double kMaxOpticalDepth = 1e4;

// tau = sigma * delta, clamped to [0, kMaxOpticalDepth].
template <typename S>
ENDORECON_HD S OpticalDepth(S sigma, S delta) {
  if (sigma <= 0 || delta <= 0) return S(0);
  const S tau = sigma * delta;
  return tau > S(kMaxOpticalDepth) ? S(kMaxOpticalDepth) : tau;
}

// d tau / d sigma: delta where tau = sigma * delta is not clamped (one-sided at sigma = 0, so a
// zero density still gets a gradient), 0 where it is (including sigma = 0 over an infinite delta).
template <typename S>
ENDORECON_HD S OpticalDepthSlope(S sigma, S delta) {
  if (sigma < 0 || delta <= 0) return S(0);
  return sigma * delta < S(kMaxOpticalDepth) ? delta : S(0);
}

template <typename S>
struct RayComposite {
  S rgb[3] = {0, 0, 0};
  S depth = 0;
  S opacity = 0;         // sum_j w_j
  S transmittance = 1;   // T after the last sample used (= 1 - opacity, computed as a product)
  int samples_used = 0;  // samples before early termination; weights beyond are 0
};

// Gradients of the loss with respect to the ray's outputs.
template <typename S>
struct RayCompositeGrad {
  S rgb[3] = {0, 0, 0};
  S depth = 0;
  S opacity = 0;
};

// Composites n samples and writes their weights w_j to weights[0..n). Early termination: before
// sample j, if T_j < min_transmittance the remaining samples are skipped (their weights written
// as 0); what they could have added is at most T_j in opacity, T_j max|c| in colour and T_j s_last
// in depth. min_transmittance = 0 never stops early.
template <typename S>
ENDORECON_HD RayComposite<S> CompositeRay(const S* sigma, const S* rgb, const S* s, const S* delta, int n,
                                          S* weights, S min_transmittance = S(0)) {
  RayComposite<S> out;
  S transmittance = 1;
  int j = 0;
  for (; j < n && !(transmittance < min_transmittance); ++j) {
    const S tau = OpticalDepth(sigma[j], delta[j]);
    const S w = transmittance * -std::expm1(-tau);
    weights[j] = w;
    out.rgb[0] += w * rgb[3 * j];
    out.rgb[1] += w * rgb[3 * j + 1];
    out.rgb[2] += w * rgb[3 * j + 2];
    out.depth += w * s[j];
    out.opacity += w;
    transmittance *= std::exp(-tau);
  }
  out.transmittance = transmittance;
  out.samples_used = j;
  for (; j < n; ++j) weights[j] = 0;
  return out;
}

// Backward of CompositeRay, given its inputs, its weights and result `forward`, and the loss
// gradients `grad` with respect to the ray's colour, depth and opacity plus, if d_weights is not
// null, d_weights[j] = dL/dw_j from losses on the weights themselves (the NLL). ADDS dL/dsigma_j to
// d_sigma[j] and dL/dc_j to d_rgb[3j..3j+2]; callers zero them first. Samples past
// forward.samples_used get nothing.
//
// With g_j = dL/dw_j in total, dL/dc_j = w_j dL/dC and
//   dL/dtau_k = g_k T_{k+1} - sum_{j>k} g_j w_j,
// evaluated in one backward sweep; T_{k+1} is rebuilt as T_final + sum_{j>k} w_j, a sum of
// non-negative terms, so it keeps its relative accuracy where the ray is nearly opaque.
template <typename S>
ENDORECON_HD void CompositeRayBackward(const S* sigma, const S* rgb, const S* s, const S* delta,
                                       const S* weights, const RayComposite<S>& forward,
                                       const RayCompositeGrad<S>& grad, const S* d_weights, S* d_sigma,
                                       S* d_rgb) {
  S transmittance_after = forward.transmittance;  // T_{k+1}
  S later = 0;                                    // sum_{j>k} g_j w_j
  for (int k = forward.samples_used - 1; k >= 0; --k) {
    const S w = weights[k];
    const S* c = rgb + 3 * k;
    S g = grad.rgb[0] * c[0] + grad.rgb[1] * c[1] + grad.rgb[2] * c[2] + grad.depth * s[k] + grad.opacity;
    if (d_weights != nullptr) g += d_weights[k];
    d_rgb[3 * k] += w * grad.rgb[0];
    d_rgb[3 * k + 1] += w * grad.rgb[1];
    d_rgb[3 * k + 2] += w * grad.rgb[2];
    const S slope = OpticalDepthSlope(sigma[k], delta[k]);
    if (slope != 0) d_sigma[k] += (g * transmittance_after - later) * slope;
    later += g * w;
    transmittance_after += w;
  }
}

// A background behind the samples (object scenes): the ray's colour gains T bg, the light the samples
// let through, with T = 1 - sum_j w_j (the transmittance after the last sample used).
template <typename S>
ENDORECON_HD void AddBackground(RayComposite<S>& ray, const S* background) {
  for (int c = 0; c < 3; ++c) ray.rgb[c] += ray.transmittance * background[c];
}

// Its backward, before CompositeRayBackward: C = sum_j w_j c_j + (1 - sum_j w_j) bg, so every weight
// also carries -bg . dL/dC, which is a gradient on the opacity sum_j w_j.
template <typename S>
ENDORECON_HD void BackgroundBackward(const S* background, RayCompositeGrad<S>& grad) {
  grad.opacity -= grad.rgb[0] * background[0] + grad.rgb[1] * background[1] + grad.rgb[2] * background[2];
}

}  // namespace endorecon::render
