// Uncertainty-guided sample reallocation along a ray (paper §3, "Samples with higher uncertainty are
// allocated additional points proportionally to their normalized uncertainty score, while a minimum
// allocation is enforced"): inverse-CDF sampling of a piecewise-constant density built from a
// coarse pass's per-sample scores (sample_score.h), with a uniform floor so no stretch of the ray
// is left without samples.
#pragma once

#include <cmath>

#include "common/hd.h"
#include "worker/engine/render/stratified_sampler.h"

namespace endorecon::render {

namespace adaptive_detail {

// The coarse pass as a piecewise-constant density on [near, far]: cell k is the stretch of ray
// closer to coarse sample k than to its neighbours (edges at midpoints, outer edges near and far).
// Cell k's probability mass is len_k (floor / L + (1 - floor) S_k / Z), Z = sum_k S_k len_k,
// L = far - near; where Z = 0 (no score anywhere) the density is uniform.
template <typename S>
struct ScoreDensity {
  const S* coarse_s;
  const S* score;
  int m;
  S near, far, floor;
  S inv_length = 0, score_scale = 0;  // 1 / L and (1 - floor) / Z

  // Edge i of the cells, i in [0, m].
  ENDORECON_HD S Edge(int i) const {
    if (i <= 0) return near;
    if (i >= m) return far;
    const S x = S(0.5) * (coarse_s[i - 1] + coarse_s[i]);
    return x < near ? near : (x > far ? far : x);
  }
  // Negative or non-finite scores count as zero: a bad score must not move samples off the ray.
  ENDORECON_HD S Score(int k) const {
    const S v = score[k];
    return v > 0 && std::isfinite(v) ? v : S(0);
  }
  ENDORECON_HD S Mass(int k, S len) const {
    const S mass = len * (floor * inv_length + score_scale * Score(k));
    return mass > 0 ? mass : S(0);
  }

  ENDORECON_HD void Prepare() {
    S z = 0;
    for (int k = 0; k < m; ++k) z += Score(k) * (Edge(k + 1) - Edge(k));
    const S length = far - near;
    inv_length = length > 0 ? S(1) / length : S(0);
    if (z > 0) {
      score_scale = (S(1) - floor) / z;
    } else {
      floor = S(1);
      score_scale = S(0);
    }
  }
};

// Walks the cumulative mass cell by cell, once, for non-decreasing targets.
template <typename S>
struct InverseCdf {
  const ScoreDensity<S>& density;
  int k = 0;
  S lo, hi, mass;  // cell k
  S before = 0;    // mass of the cells before cell k

  ENDORECON_HD explicit InverseCdf(const ScoreDensity<S>& d)
      : density(d), lo(d.Edge(0)), hi(d.Edge(1)), mass(d.Mass(0, hi - lo)) {}

  ENDORECON_HD S operator()(S target) {
    while (k + 1 < density.m && before + mass <= target) {
      before += mass;
      ++k;
      lo = hi;
      hi = density.Edge(k + 1);
      mass = density.Mass(k, hi - lo);
    }
    if (!(mass > 0)) return lo;
    const S x = lo + (target - before) / mass * (hi - lo);
    return x < lo ? lo : (x > hi ? hi : x);
  }
};

}  // namespace adaptive_detail

// Reallocates n samples over [near, far] from m ascending coarse samples coarse_s[0..m) with
// scores score[0..m) (>= 0; the normalised sample score S = s~_sigma^2 + lambda s~_c^2). A fraction
// `floor` in (0, 1] of the mass is spread uniformly over [near, far], the rest in proportion to the
// score, so any stretch of ray holding a fraction p of its length gets at least floor * p * n samples
// (stratified, so this holds per draw up to one sample). Samples are drawn stratified in CDF space:
// sample j at quantile (j + uniform(first_draw + j)) / n, and its interval is the stretch between
// quantiles j / n and (j + 1) / n, so the output is ascending and its intervals tile [near, far]
// (ray_samples.h). The new samples replace the coarse ones: evaluate the field at all of them.
// With no coarse samples (m = 0) this is StratifiedSamples.
template <typename S, typename Uniform>
ENDORECON_HD void AdaptiveSamples(const S* coarse_s, const S* score, int m, S near, S far, S floor, int n,
                                  const Uniform& uniform, S* s, S* delta, unsigned first_draw = 0) {
  if (m <= 0) {
    StratifiedSamples(near, far, n, uniform, s, delta, first_draw);
    return;
  }
  adaptive_detail::ScoreDensity<S> density{coarse_s, score, m, near, far, floor};
  density.Prepare();
  adaptive_detail::InverseCdf<S> invert(density);
  S lower_edge = near;
  for (int j = 0; j < n; ++j) {
    const S u = static_cast<S>(uniform(static_cast<unsigned>(first_draw + j)));
    const S x = invert((S(j) + u) / S(n));
    const S upper_edge = j + 1 == n ? far : invert(S(j + 1) / S(n));
    s[j] = x;
    delta[j] = upper_edge > lower_edge ? upper_edge - lower_edge : S(0);
    lower_edge = upper_edge > lower_edge ? upper_edge : lower_edge;
  }
}

}  // namespace endorecon::render
