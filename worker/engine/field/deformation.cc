#include "worker/engine/field/deformation.h"

#include <algorithm>
#include <string>

#include "common/error.h"
#include "worker/engine/field/hash_math.h"

namespace endorecon::field {
namespace {

// The time interval of t: slices `knot` and `knot + 1` with weights 1 - frac and frac.
template <typename S>
int TimeInterval(S t, int knots, S* frac) {
  return static_cast<int>(CellOf(ClampUnit(t), static_cast<std::uint32_t>(knots), frac));
}

// The spatial grid of every time slice: dense, (resolution + 1)^3 vertices.
GridLevel SpatialLevel(const DeformationConfig& config) {
  GridLevel level;
  level.res = static_cast<std::uint32_t>(config.resolution);
  level.dense = 1;
  return level;
}

}  // namespace

template <typename S>
Deformation<S>::Deformation(const DeformationConfig& config) : config_(config) {
  if (config.resolution < 1 || config.time_knots < 1) {
    FailInvalid("deformation grid needs resolution and time_knots >= 1, got " +
                std::to_string(config.resolution) + " and " + std::to_string(config.time_knots));
  }
  const std::size_t side = static_cast<std::size_t>(config.resolution) + 1;
  slice_size_ = side * side * side * 3;
}

template <typename S>
void Deformation<S>::Init(S* params) const {
  std::fill_n(params, param_count(), S(0));
}

template <typename S>
void Deformation<S>::Forward(const S* params, const S* pos, const S* t, int n, S* x0) const {
  const GridLevel level = SpatialLevel(config_);
  for (int i = 0; i < n; ++i) {
    std::uint32_t slot[8];
    S w[8], frac[3], ft;
    CellCornersOf<true>(level, pos + 3 * i, slot, w, frac);
    const int knot = TimeInterval(t[i], config_.time_knots, &ft);
    S dx[3] = {};
    for (int side = 0; side < 2; ++side) {
      const int slice = knot + side;  // slice 0 is the fixed zero at t = 0
      if (slice == 0) continue;
      const S wt = side ? ft : S(1) - ft;
      const S* table = params + (slice - 1) * slice_size_;
      for (int k = 0; k < 8; ++k) {
        const S* v = table + std::size_t{slot[k]} * 3;
        for (int a = 0; a < 3; ++a) dx[a] += wt * w[k] * v[a];
      }
    }
    for (int a = 0; a < 3; ++a) x0[3 * i + a] = pos[3 * i + a] + dx[a];
  }
}

template <typename S>
void Deformation<S>::BackwardKnot(int knot, const S* pos, const S* t, int n, const S* dx0, S* grads) const {
  const GridLevel level = SpatialLevel(config_);
  S* table = grads + (knot - 1) * slice_size_;
  for (int i = 0; i < n; ++i) {
    S ft;
    const int interval = TimeInterval(t[i], config_.time_knots, &ft);
    if (interval != knot && interval + 1 != knot) continue;
    const S wt = interval == knot ? S(1) - ft : ft;
    std::uint32_t slot[8];
    S w[8], frac[3];
    CellCornersOf<true>(level, pos + 3 * i, slot, w, frac);
    for (int k = 0; k < 8; ++k) {
      S* v = table + std::size_t{slot[k]} * 3;
      for (int a = 0; a < 3; ++a) v[a] += wt * w[k] * dx0[3 * i + a];
    }
  }
}

template <typename S>
void Deformation<S>::BackwardPosition(const S* params, const S* pos, const S* t, int n, const S* dx0,
                                      S* dpos) const {
  const GridLevel level = SpatialLevel(config_);
  const S res = static_cast<S>(config_.resolution);
  for (int i = 0; i < n; ++i) {
    std::uint32_t slot[8];
    S w[8], frac[3], ft;
    CellCornersOf<true>(level, pos + 3 * i, slot, w, frac);
    const int knot = TimeInterval(t[i], config_.time_knots, &ft);
    const S* g = dx0 + 3 * i;
    S dot[8] = {};  // (dx . g) at each corner, both time slices blended
    for (int side = 0; side < 2; ++side) {
      const int slice = knot + side;
      if (slice == 0) continue;
      const S wt = side ? ft : S(1) - ft;
      const S* table = params + (slice - 1) * slice_size_;
      for (int k = 0; k < 8; ++k) {
        const S* v = table + std::size_t{slot[k]} * 3;
        dot[k] += wt * (v[0] * g[0] + v[1] * g[1] + v[2] * g[2]);
      }
    }
    S grad[3];
    TrilinearGradient(dot, frac, grad);
    for (int a = 0; a < 3; ++a) {
      dpos[3 * i + a] += g[a] + (InsideUnit(pos[3 * i + a]) ? res * grad[a] : S(0));
    }
  }
}

template class Deformation<float>;
template class Deformation<double>;

}  // namespace endorecon::field
