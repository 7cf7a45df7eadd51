// A background learned per ray direction (background_math.h has the per-ray math): for captures whose
// backdrop is neither black nor white (train_config.h "background": "learned"). A module of the field
// (module.h) whose "samples" are rays: its input is a ray's unit direction, its output the colour the
// ray sees past its samples. Init sets the parameters to zero (a grey of 0.5 in every direction); the
// trainer then starts them from the clip (train/background_start.h).
#pragma once

#include <cstddef>
#include <cstdint>

#include "worker/engine/field/batch_loop.h"
#include "worker/engine/field/module.h"

namespace endorecon::field {

template <typename S>
class Background {
 public:
  struct Inputs {
    int n = 0;
    const S* dir = nullptr;  // n x 3, unit ray directions
  };
  struct Outputs {
    S* rgb = nullptr;  // n x 3, in (0, 1)
  };
  struct OutputGrads {
    const S* drgb = nullptr;  // n x 3
  };
  struct InputGrads {};  // directions are data

  std::size_t param_count() const;

  void Init(S* params, std::uint64_t seed) const;
  void Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass& pass);
  // Reads out.rgb of the Forward (or of BackgroundSample in the training step) with the same inputs.
  void Backward(const S* params, const Inputs& in, const Outputs& out, const OutputGrads& grad, S* dparams,
                const InputGrads& din, const DropoutPass& pass);

 private:
  TaskPartials<S> partials_;
};

}  // namespace endorecon::field
