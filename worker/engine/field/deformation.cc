#include "worker/engine/field/deformation.h"

#include <algorithm>
#include <string>

#include "common/error.h"
#include "worker/engine/field/batch_loop.h"
#include "worker/engine/field/hash_math.h"

namespace endorecon::field {

static_assert(TrainableModule<Deformation<float>, float>);

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
void Deformation<S>::Init(S* params, std::uint64_t) const {
  std::fill_n(params, param_count(), S(0));
}

template <typename S>
void Deformation<S>::Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass&) {
  const GridLevel level = SpatialLevel(config_);
  ParallelRows(in.n, [&](std::size_t i) {
    std::uint32_t slot[8];
    S w[8], frac[3], ft;
    CellCornersOf<true>(level, in.pos + 3 * i, slot, w, frac);
    const int knot = TimeInterval(in.time[i], config_.time_knots, &ft);
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
    for (int a = 0; a < 3; ++a) out.x0[3 * i + a] = in.pos[3 * i + a] + dx[a];
  });
}

template <typename S>
void Deformation<S>::BackwardKnot(int knot, const Inputs& in, const S* dx0, S* dparams) const {
  const GridLevel level = SpatialLevel(config_);
  S* table = dparams + (knot - 1) * slice_size_;
  for (int i = 0; i < in.n; ++i) {
    S ft;
    const int interval = TimeInterval(in.time[i], config_.time_knots, &ft);
    if (interval != knot && interval + 1 != knot) continue;
    const S wt = interval == knot ? S(1) - ft : ft;
    std::uint32_t slot[8];
    S w[8], frac[3];
    CellCornersOf<true>(level, in.pos + 3 * i, slot, w, frac);
    for (int k = 0; k < 8; ++k) {
      S* v = table + std::size_t{slot[k]} * 3;
      for (int a = 0; a < 3; ++a) v[a] += wt * w[k] * dx0[3 * i + a];
    }
  }
}

template <typename S>
void Deformation<S>::Backward(const S* params, const Inputs& in, const Outputs&, const OutputGrads& grad,
                              S* dparams, const InputGrads& din, const DropoutPass&) {
  tbb::parallel_for(1, config_.time_knots + 1, [&](int knot) { BackwardKnot(knot, in, grad.dx0, dparams); });
  if (!din.dpos) return;
  const GridLevel level = SpatialLevel(config_);
  const S res = static_cast<S>(config_.resolution);
  ParallelRows(in.n, [&](std::size_t i) {
    std::uint32_t slot[8];
    S w[8], frac[3], ft;
    CellCornersOf<true>(level, in.pos + 3 * i, slot, w, frac);
    const int knot = TimeInterval(in.time[i], config_.time_knots, &ft);
    const S* g = grad.dx0 + 3 * i;
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
    S gradient[3];
    TrilinearGradient(dot, frac, gradient);
    for (int a = 0; a < 3; ++a) {
      din.dpos[3 * i + a] = g[a] + (InsideUnit(in.pos[3 * i + a]) ? res * gradient[a] : S(0));
    }
  });
}

template class Deformation<float>;
template class Deformation<double>;

}  // namespace endorecon::field
