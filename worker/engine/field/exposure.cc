#include "worker/engine/field/exposure.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "common/error.h"
#include "worker/engine/field/exposure_math.h"
#include "worker/engine/field/hash_math.h"

namespace endorecon::field {

static_assert(TrainableModule<Exposure<float>, float>);

template <typename S>
Exposure<S>::Exposure(std::vector<float> times) : times_(std::move(times)) {
  if (times_.empty()) FailInvalid("field.exposure_times: the exposure needs at least one knot");
  CheckExposureTimes(times_);
}

template <typename S>
void Exposure<S>::Init(S* params, std::uint64_t) const {
  std::fill_n(params, param_count(), S(0));
}

template <typename S>
void Exposure<S>::Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass&) {
  const float* times = times_.data();
  const int knots = this->knots();
  S prior[kExposurePriorSize];  // computed per call: calls on other rows may run at once
  ExposurePrior(params, knots, prior);
  // A ray's samples share its time (and a rendered frame's rays theirs): the gains are computed once
  // per run of equal times, not per sample (three exp and a knot search each).
  ParallelTasks(in.n, kTaskRows, [&](int, int row0, int rows) {
    S gain[3];
    S gain_time = std::numeric_limits<S>::quiet_NaN();  // no time equals it: the first row computes
    for (std::size_t i = static_cast<std::size_t>(row0); i < static_cast<std::size_t>(row0 + rows); ++i) {
      if (!(in.time[i] == gain_time)) {
        gain_time = in.time[i];
        ExposureGains(params, prior, times, knots, gain_time, gain);
      }
      for (int c = 0; c < 3; ++c) out.rgb[3 * i + c] = gain[c] * in.rgb[3 * i + c];
    }
  });
}

template <typename S>
void Exposure<S>::Backward(const S* params, const Inputs& in, const Outputs&, const OutputGrads& grad,
                           S* dparams, const InputGrads& din, const DropoutPass&) {
  if (!grad.drgb) {
    if (din.drgb) std::fill_n(din.drgb, 3 * static_cast<std::size_t>(in.n), S(0));
    return;
  }
  const float* times = times_.data();
  const int knots = this->knots();
  S prior[kExposurePriorSize];
  ExposurePrior(params, knots, prior);
  // The knots are few and every sample adds to one or two, and to the prior's four values: a
  // partial block per task, added in order, then the prior's gradient chained to every knot.
  const std::size_t size = param_count() + kExposurePriorSize;
  partials_.Reset(TaskCount(in.n, kTaskRows), size);
  ParallelTasks(in.n, kTaskRows, [&](int task, int row0, int rows) {
    S* partial = partials_.task(task);
    for (std::size_t i = static_cast<std::size_t>(row0); i < static_cast<std::size_t>(row0 + rows); ++i) {
      ExposureSampleBackward(params, prior, times, knots, in.time[i], in.rgb + 3 * i, grad.drgb + 3 * i,
                             din.drgb ? din.drgb + 3 * i : static_cast<S*>(nullptr), partial,
                             partial + param_count(), PlainAdd{});
    }
  });
  GrowTo(sums_, size);
  std::fill(sums_.begin(), sums_.end(), S(0));
  partials_.AddTo(sums_.data());
  for (std::size_t k = 0; k < param_count(); ++k) dparams[k] += sums_[k];
  ExposurePriorBackward(params, knots, prior, sums_.data() + param_count(), dparams);
}

template class Exposure<float>;
template class Exposure<double>;

}  // namespace endorecon::field
