// Per-sample math of the 4D deformation grid (deformation.h), written once for the CPU module's loops
// and the CUDA kernels: time slice k (1..knots) of the parameters holds a dense (res + 1)^3 x 3 grid of
// displacements at t = k / knots; slice 0, at t = 0, is a fixed zero and not stored.
#pragma once

#include <cstddef>
#include <cstdint>

#include "common/hd.h"
#include "worker/engine/field/hash_math.h"

namespace endorecon::field {

// The layout of the grid: `res` cells per axis, `knots` time intervals, `slice` scalars per slice.
struct DeformationLayout {
  std::uint32_t res = 1;
  int knots = 1;
  std::size_t slice = 0;  // (res + 1)^3 * 3

  ENDORECON_HD GridLevel Level() const {
    GridLevel level;
    level.res = res;
    level.dense = 1;
    return level;
  }
};

// The time interval of t (clamped into [0, 1], NaN read as 0): slices `interval` and `interval + 1`
// with weights 1 - *frac and *frac.
template <typename S>
ENDORECON_HD int TimeInterval(S t, int knots, S* frac) {
  return static_cast<int>(CellOf(ClampUnit(t), static_cast<std::uint32_t>(knots), frac));
}

// x0 = pos + dx(pos, t) for one sample (3 values each).
template <typename S>
ENDORECON_HD void DeformSample(const DeformationLayout& layout, const S* params, const S* pos, S t, S* x0) {
  std::uint32_t slot[8];
  S w[8], frac[3], ft;
  CellCornersOf<true>(layout.Level(), pos, slot, w, frac);
  const int interval = TimeInterval(t, layout.knots, &ft);
  S dx[3] = {};
  for (int side = 0; side < 2; ++side) {
    const int slice = interval + side;
    if (slice == 0) continue;
    const S wt = side ? ft : S(1) - ft;
    const S* table = params + (slice - 1) * layout.slice;
    for (int k = 0; k < 8; ++k) {
      const S* v = table + static_cast<std::size_t>(slot[k]) * 3;
      for (int a = 0; a < 3; ++a) dx[a] += wt * w[k] * v[a];
    }
  }
  for (int a = 0; a < 3; ++a) x0[a] = pos[a] + dx[a];
}

// The (up to 16) parameters' vertices and weights DeformSample blends for one sample: dx =
// sum_j weight[j] * params[vertex[j] * 3 + a], vertex[j] counted over the stored slices (slice k's
// vertices from (k - 1) * slice / 3). Returns how many (the t = 0 slice is not stored). For fits
// that need the grid as a linear map (train/flow_start.h), not for the hot path.
template <typename S>
ENDORECON_HD int DeformWeights(const DeformationLayout& layout, const S* pos, S t, std::size_t* vertex,
                               S* weight) {
  std::uint32_t slot[8];
  S w[8], frac[3], ft;
  CellCornersOf<true>(layout.Level(), pos, slot, w, frac);
  const int interval = TimeInterval(t, layout.knots, &ft);
  int n = 0;
  for (int side = 0; side < 2; ++side) {
    const int slice = interval + side;
    if (slice == 0) continue;
    const S wt = side ? ft : S(1) - ft;
    const std::size_t first = static_cast<std::size_t>(slice - 1) * (layout.slice / 3);
    for (int k = 0; k < 8; ++k) {
      vertex[n] = first + slot[k];
      weight[n++] = wt * w[k];
    }
  }
  return n;
}

// Adds one sample's dL/dparams, given dx0 = dL/dx0 (3 values), to the slices it touches, through
// add(pointer, value) (PlainAdd on the CPU, atomic in kernels). only_knot > 0 restricts it to that
// slice (the CPU runs one slice per task, so tasks write disjoint parts).
template <typename S, typename Add>
ENDORECON_HD void DeformScatterSample(const DeformationLayout& layout, const S* pos, S t, const S* dx0,
                                      S* grads, int only_knot, const Add& add) {
  S ft;
  const int interval = TimeInterval(t, layout.knots, &ft);
  if (only_knot > 0 && interval != only_knot && interval + 1 != only_knot) return;
  std::uint32_t slot[8];
  S w[8], frac[3];
  CellCornersOf<true>(layout.Level(), pos, slot, w, frac);
  for (int side = 0; side < 2; ++side) {
    const int slice = interval + side;
    if (slice == 0 || (only_knot > 0 && slice != only_knot)) continue;
    const S wt = side ? ft : S(1) - ft;
    S* table = grads + (slice - 1) * layout.slice;
    for (int k = 0; k < 8; ++k) {
      S* v = table + static_cast<std::size_t>(slot[k]) * 3;
      for (int a = 0; a < 3; ++a) add(v + a, wt * w[k] * dx0[a]);
    }
  }
}

// dL/dpos (3 values, written) = dx0 + (d dx / d pos)^T dx0 for one sample.
template <typename S>
ENDORECON_HD void DeformPositionGradient(const DeformationLayout& layout, const S* params, const S* pos, S t,
                                         const S* dx0, S* dpos) {
  std::uint32_t slot[8];
  S w[8], frac[3], ft;
  CellCornersOf<true>(layout.Level(), pos, slot, w, frac);
  const int interval = TimeInterval(t, layout.knots, &ft);
  S dot[8] = {};  // (dx . dx0) at each corner, both time slices blended
  for (int side = 0; side < 2; ++side) {
    const int slice = interval + side;
    if (slice == 0) continue;
    const S wt = side ? ft : S(1) - ft;
    const S* table = params + (slice - 1) * layout.slice;
    for (int k = 0; k < 8; ++k) {
      const S* v = table + static_cast<std::size_t>(slot[k]) * 3;
      dot[k] += wt * (v[0] * dx0[0] + v[1] * dx0[1] + v[2] * dx0[2]);
    }
  }
  S gradient[3];
  TrilinearGradient(dot, frac, gradient);
  const S res = static_cast<S>(layout.res);
  for (int a = 0; a < 3; ++a) dpos[a] = dx0[a] + (InsideUnit(pos[a]) ? res * gradient[a] : S(0));
}

}  // namespace endorecon::field
