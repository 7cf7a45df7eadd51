#include "worker/engine/field/deformation.h"

#include <algorithm>
#include <string>

#include "common/error.h"
#include "worker/engine/field/batch_loop.h"
#include "worker/engine/field/deformation_math.h"

namespace endorecon::field {

static_assert(TrainableModule<Deformation<float>, float>);

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
  const DeformationLayout layout = this->layout();
  ParallelRows(
      in.n, [&](std::size_t i) { DeformSample(layout, params, in.pos + 3 * i, in.time[i], out.x0 + 3 * i); });
}

template <typename S>
void Deformation<S>::Backward(const S* params, const Inputs& in, const Outputs&, const OutputGrads& grad,
                              S* dparams, const InputGrads& din, const DropoutPass&) {
  const DeformationLayout layout = this->layout();
  // One time slice per task: the slices are disjoint parts of dparams.
  tbb::parallel_for(1, config_.time_knots + 1, [&](int knot) {
    for (std::size_t i = 0; i < static_cast<std::size_t>(in.n); ++i) {
      DeformScatterSample(layout, in.pos + 3 * i, in.time[i], grad.dx0 + 3 * i, dparams, knot, PlainAdd{});
    }
  });
  if (!din.dpos) return;
  ParallelRows(in.n, [&](std::size_t i) {
    DeformPositionGradient(layout, params, in.pos + 3 * i, in.time[i], grad.dx0 + 3 * i, din.dpos + 3 * i);
  });
}

template class Deformation<float>;
template class Deformation<double>;

}  // namespace endorecon::field
