// Deformation to canonical space, dx = G(x, t), as a 4D grid: `resolution`^3 cells in space times
// `time_knots` intervals in t, 3 values per vertex, quadrilinear interpolation. The time slice at t = 0
// is fixed at zero (not a parameter), so dx is exactly 0 at t = 0 as the method requires.
// Why a grid and not EndoNeRF's MLP on positional encodings: that network costs ~0.5 M multiply-adds
// per sample, ~100x the whole CPU field budget; the grid costs 16 reads and 48 multiply-adds per
// sample (the same again backward), is linear in its parameters (starts at exactly zero motion, and
// its gradient is a scatter), and tissue motion is smooth enough for 16^3 spatial cells.
// A module of the field (module.h).
#pragma once

#include <cstddef>
#include <cstdint>

#include "worker/engine/field/module.h"

namespace endorecon::field {

struct DeformationConfig {
  bool enabled = true;  // false for a static scene: the field never builds or runs the deformation
  int resolution = 16;  // cells per spatial axis
  int time_knots = 8;   // intervals in t; knot k sits at t = k / time_knots
};

template <typename S>
class Deformation {
 public:
  struct Inputs {
    int n = 0;
    const S* pos = nullptr;   // n x 3, clamped into [0, 1] for the lookup, NaN read as 0
    const S* time = nullptr;  // n, likewise
  };
  struct Outputs {
    S* x0 = nullptr;  // n x 3: pos + dx(pos, t), not clamped (the hash grids clamp and stop the gradient)
  };
  struct OutputGrads {
    const S* dx0 = nullptr;  // n x 3
  };
  struct InputGrads {
    S* dpos = nullptr;  // n x 3: dL/dpos = dx0 + (d dx / d pos)^T dx0
  };

  // Throws Error(kInvalidArgument) for resolution or time_knots < 1.
  explicit Deformation(const DeformationConfig& config);

  const DeformationConfig& config() const { return config_; }
  std::size_t param_count() const { return slice_size_ * config_.time_knots; }

  // All zero whatever the seed: no motion until training finds some.
  void Init(S* params, std::uint64_t seed) const;

  void Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass& pass);
  // The parameters' gradient is scattered one time slice per task (slices are disjoint).
  void Backward(const S* params, const Inputs& in, const Outputs& out, const OutputGrads& grad, S* dparams,
                const InputGrads& din, const DropoutPass& pass);

 private:
  // Adds to dparams the part of the gradient that lies in time slice `knot` (1..time_knots).
  void BackwardKnot(int knot, const Inputs& in, const S* dx0, S* dparams) const;

  DeformationConfig config_;
  std::size_t slice_size_ = 0;  // scalars per time slice: (resolution + 1)^3 * 3
};

}  // namespace endorecon::field
