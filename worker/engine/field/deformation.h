// Deformation to canonical space, dx = G(x, t), as a 4D grid: `resolution`^3 cells in space times
// `time_knots` intervals in t, 3 values per vertex, quadrilinear interpolation. The time slice at t = 0
// is fixed at zero (not a parameter), so dx is exactly 0 at t = 0 as the method requires.
// Why a grid and not EndoNeRF's MLP on positional encodings: that network costs ~0.5 M multiply-adds
// per sample, ~100x the whole CPU field budget; the grid costs 16 reads and 48 multiply-adds per
// sample (the same again backward), is linear in its parameters (starts at exactly zero motion, and
// its gradient is a scatter), and tissue motion is smooth enough for 16^3 spatial cells.
#pragma once

#include <cstddef>
#include <cstdint>

namespace endorecon::field {

struct DeformationConfig {
  bool enabled = true;  // false for a static scene: the field never builds or runs the deformation
  int resolution = 16;  // cells per spatial axis
  int time_knots = 8;   // intervals in t; knot k sits at t = k / time_knots
};

template <typename S>
class Deformation {
 public:
  // Throws Error(kInvalidArgument) for resolution or time_knots < 1.
  explicit Deformation(const DeformationConfig& config);

  const DeformationConfig& config() const { return config_; }
  std::size_t param_count() const { return slice_size_ * config_.time_knots; }

  // All zero: no motion until training finds some.
  void Init(S* params) const;

  // x0 = x + dx(x, t) for n samples (pos n x 3, t n values, both clamped into [0, 1] for the lookup,
  // NaN read as 0). x0 is not clamped: the hash grids clamp (and stop the gradient) themselves.
  void Forward(const S* params, const S* pos, const S* t, int n, S* x0) const;

  // Adds to grads the part of dL/dparams that lies in time slice `knot` (1..time_knots) given
  // dx0 = dL/dx0 (n x 3). Slices are disjoint, so different knots may run on different threads.
  void BackwardKnot(int knot, const S* pos, const S* t, int n, const S* dx0, S* grads) const;

  // dpos += dL/dx = dx0 + (d dx / d x)^T dx0.
  void BackwardPosition(const S* params, const S* pos, const S* t, int n, const S* dx0, S* dpos) const;

 private:
  DeformationConfig config_;
  std::size_t slice_size_ = 0;  // scalars per time slice: (resolution + 1)^3 * 3
};

}  // namespace endorecon::field
