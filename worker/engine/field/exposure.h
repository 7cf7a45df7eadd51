// Exposure apart from motion: per-channel camera gains at knots in time (the training frames'), applied
// to the colour head's output (exposure_math.h has the per-sample math). The log-gains start at zero (a
// gain of 1). A module of the field (module.h); the field leaves it out when it has no knot times.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "worker/engine/field/batch_loop.h"
#include "worker/engine/field/exposure_times.h"
#include "worker/engine/field/module.h"

namespace endorecon::field {

template <typename S>
class Exposure {
 public:
  struct Inputs {
    int n = 0;
    const S* time = nullptr;  // n
    const S* rgb = nullptr;   // n x 3, the colour head's
  };
  struct Outputs {
    S* rgb = nullptr;  // n x 3, as the camera sees it
  };
  struct OutputGrads {
    const S* drgb = nullptr;  // n x 3
  };
  struct InputGrads {
    S* drgb = nullptr;  // n x 3, or null
  };

  // `times`: the knots' times, ascending, at least one. Throws Error(kInvalidArgument) otherwise.
  explicit Exposure(std::vector<float> times);

  int knots() const { return static_cast<int>(times_.size()); }
  const std::vector<float>& times() const { return times_; }
  std::size_t param_count() const { return 3 * times_.size(); }

  void Init(S* params, std::uint64_t seed) const;
  void Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass& pass);
  void Backward(const S* params, const Inputs& in, const Outputs& out, const OutputGrads& grad, S* dparams,
                const InputGrads& din, const DropoutPass& pass);

 private:
  std::vector<float> times_;
  TaskPartials<S> partials_;
  AlignedVector<S> sums_;  // the partials' sum: the knots' gradients, then the prior's
};

}  // namespace endorecon::field
