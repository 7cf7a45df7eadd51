// Depth-guided sampling (EndoNeRF): most samples from a Gaussian of width xi around the ray's prior
// depth, plus a few stratified ones so the empty space in front of and behind the surface is still
// seen (and its density still pushed towards zero).
//
// Training only: the prior is a measurement of the frame being rendered, so rendering a held-out
// frame or a novel view must not use it. Test-time callers use StratifiedSamples (or the adaptive
// sampler on a stratified coarse pass) instead; choosing is the caller's job.
#pragma once

#include <cmath>

#include "common/hd.h"
#include "worker/engine/base/counter_rng.h"
#include "worker/engine/render/ray_samples.h"
#include "worker/engine/render/stratified_sampler.h"

namespace endorecon::render {

template <typename S>
struct DepthGuidedConfig {
  S xi = S(1);                 // standard deviation of the Gaussian, in depth units
  int gaussian_samples = 56;   // drawn around the prior
  int stratified_samples = 8;  // spread over [near, far]
};

// Writes n = gaussian_samples + stratified_samples ascending samples s[0..n) in [near, far] and
// their intervals delta[0..n) (midpoint intervals clipped to [near, far], see ray_samples.h);
// returns n. Gaussian draws outside [near, far] are clamped onto its ends (those samples may get
// zero-length intervals). Draw indices used: stratified sample j takes uniform(j), Gaussian sample
// i takes uniform(stratified_samples + 2i) and uniform(stratified_samples + 2i + 1).
// A prior that is unknown (<= 0, the depth maps' "no value") or not finite gives n stratified
// samples instead, so one call serves every pixel of a clip with holes in its depth.
// The Gaussian part alone: count draws around the prior, clamped onto [near, far], into s[0..count)
// (unsorted, no intervals). Draw i takes uniform(first_draw + 2i) and uniform(first_draw + 2i + 1):
// with first_draw = stratified_samples these are DepthGuidedSamples' own Gaussian samples.
template <typename S, typename Uniform>
ENDORECON_HD void GaussianSamplesAround(S near, S far, S prior_depth, S xi, int count, const Uniform& uniform,
                                        unsigned first_draw, S* s) {
  for (int i = 0; i < count; ++i) {
    const S u1 = static_cast<S>(uniform(static_cast<unsigned>(first_draw + 2 * i)));
    const S u2 = static_cast<S>(uniform(static_cast<unsigned>(first_draw + 2 * i + 1)));
    const S x = prior_depth + xi * base::NormalFromUniforms(u1, u2);
    s[i] = x < near ? near : (x > far ? far : x);
  }
}

template <typename S, typename Uniform>
ENDORECON_HD int DepthGuidedSamples(S near, S far, S prior_depth, const DepthGuidedConfig<S>& config,
                                    const Uniform& uniform, S* s, S* delta) {
  const int n = config.gaussian_samples + config.stratified_samples;
  if (!(prior_depth > 0) || !std::isfinite(prior_depth)) {
    StratifiedSamples(near, far, n, uniform, s, delta);
    return n;
  }
  const int ns = config.stratified_samples;
  StratifiedSamples(near, far, ns, uniform, s, delta);
  GaussianSamplesAround(near, far, prior_depth, config.xi, config.gaussian_samples, uniform, unsigned(ns),
                        s + ns);
  SortAscending(s, n);
  MidpointIntervals(s, n, near, far, delta);
  return n;
}

}  // namespace endorecon::render
