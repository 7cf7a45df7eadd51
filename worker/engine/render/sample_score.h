// Per-sample and per-ray uncertainty scores (paper §3): per-ray min-max normalisation of the
// density and colour variances, the sample score S_j = s~_sigma,j^2 + lambda s~_c,j^2 that drives
// AdaptiveSamples, and the opacity-weighted ray score that drives uncertainty-guided ray selection.
#pragma once

#include <cmath>

#include "common/hd.h"

namespace endorecon::render {

template <typename S>
struct ValueRange {
  S lo, hi;
};

// The smallest and largest of v[0..n), ignoring NaN; {0, 0} for n = 0.
template <typename S>
ENDORECON_HD ValueRange<S> RangeOf(const S* v, int n) {
  ValueRange<S> r{S(0), S(0)};
  bool any = false;
  for (int j = 0; j < n; ++j) {
    if (v[j] != v[j]) continue;
    if (!any || v[j] < r.lo) r.lo = v[j];
    if (!any || v[j] > r.hi) r.hi = v[j];
    any = true;
  }
  return r;
}

// (v - lo) / (hi - lo + eps), in [0, 1]. A constant vector (hi = lo) maps to 0 even with eps = 0,
// and so does anything that is not finite (a NaN or an infinite range): never NaN.
template <typename S>
ENDORECON_HD S MinMaxNormalized(S v, ValueRange<S> range, S eps) {
  const S denominator = range.hi - range.lo + eps;
  if (!(denominator > 0) || !std::isfinite(denominator)) return S(0);
  const S x = (v - range.lo) / denominator;
  return x > 0 ? (x < 1 ? x : S(1)) : S(0);
}

// out[j] = MinMaxNormalized(v[j]) over the range of v[0..n); out may be v.
template <typename S>
ENDORECON_HD void MinMaxNormalize(const S* v, int n, S eps, S* out) {
  const ValueRange<S> range = RangeOf(v, n);
  for (int j = 0; j < n; ++j) out[j] = MinMaxNormalized(v[j], range, eps);
}

// score[j] = s~_sigma,j^2 + lambda s~_c,j^2 from the total (aleatoric + epistemic) density and colour
// variances of one ray's samples, each min-max normalised over the ray. Each score is in
// [0, 1 + lambda]; score may alias neither input.
template <typename S>
ENDORECON_HD void SampleScores(const S* var_density, const S* var_color, int n, S lambda, S eps, S* score) {
  const ValueRange<S> density_range = RangeOf(var_density, n);
  const ValueRange<S> color_range = RangeOf(var_color, n);
  for (int j = 0; j < n; ++j) {
    score[j] = MinMaxNormalized(var_density[j], density_range, eps) +
               lambda * MinMaxNormalized(var_color[j], color_range, eps);
  }
}

// S_ray = sum_j w_j (var_density_j + lambda var_color_j) / sum_j w_j, with the rendering weights
// w_j = T_j alpha_j and the raw (not normalised) variances, as the paper's ray-level equation.
// A ray with no opacity (sum_j w_j = 0: it hits nothing) scores 0.
template <typename S>
ENDORECON_HD S RayScore(const S* weights, const S* var_density, const S* var_color, int n, S lambda) {
  S weighted = 0, total = 0;
  for (int j = 0; j < n; ++j) {
    weighted += weights[j] * (var_density[j] + lambda * var_color[j]);
    total += weights[j];
  }
  return total > 0 ? weighted / total : S(0);
}

}  // namespace endorecon::render
