// The ensemble of hash grids the paper blends in time: G grids with their own base resolution and
// per-level scale, sharing levels, features per level and table size, and their blend
// f = sum_i beta_i H_i(x) with per-sample weights beta (TemporalBlend makes them from t). Each grid's
// output is padded to the same width D = (most levels any grid keeps) x F, so the blend can sum them;
// a level a grid left out (above the resolution cap) reads as 0. A module of the field (module.h).
// The blend is here, not in TemporalBlend, so the table gradient is one scatter of beta_i * df per
// (grid, level) instead of a materialised G x D gradient per sample.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "worker/engine/field/batch_loop.h"
#include "worker/engine/field/hash_grid.h"
#include "worker/engine/field/module.h"

namespace endorecon::field {

struct GridEnsembleConfig {
  std::vector<int> base_resolutions = {8, 16, 32};
  std::vector<double> scales = {1.4, 1.7, 1.9};
  int levels = 16;
  int features = 8;
  int log2_table = 19;
  int max_resolution = 0;  // 0: no cap; see HashGridConfig

  HashGridConfig Grid(int i) const;
};

template <typename S>
class GridEnsemble {
 public:
  struct Inputs {
    int n = 0;
    const S* pos = nullptr;   // n x 3 (clamped into [0, 1]^3 for the lookups; NaN read as 0)
    const S* beta = nullptr;  // n x G blend weights
  };
  struct Outputs {
    S* feats = nullptr;  // n x (G * D): grid 0's D values, then grid 1's, ... (kept for dL/dbeta)
    S* f = nullptr;      // n x D: the blend
  };
  struct OutputGrads {
    const S* df = nullptr;  // n x D
  };
  struct InputGrads {
    S* dpos = nullptr;   // n x 3
    S* dbeta = nullptr;  // n x G
  };

  // Throws Error(kInvalidArgument) when the two lists differ in length or are empty, or a grid is bad.
  explicit GridEnsemble(const GridEnsembleConfig& config);

  int grids() const { return static_cast<int>(grids_.size()); }
  const HashGrid<S>& grid(int i) const { return grids_[i]; }
  std::size_t grid_offset(int i) const { return offsets_[i]; }  // grid i's table within params
  int feature_dim() const { return feature_dim_; }              // D
  int output_dim() const { return grids() * feature_dim_; }     // G * D
  std::size_t param_count() const { return param_count_; }

  void Init(S* params, std::uint64_t seed) const;

  // Parallel over tasks of samples; each task walks every grid's levels over its samples, then blends.
  void Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass& pass);
  // Parallel over (grid, level): each task scatters beta_g * df into its own part of dparams. With
  // din.dpos the level tasks are dealt round-robin into a fixed number of groups, each adding into its
  // own n x 3 buffer, summed in group order: the result does not depend on the thread count.
  void Backward(const S* params, const Inputs& in, const Outputs& out, const OutputGrads& grad, S* dparams,
                const InputGrads& din, const DropoutPass& pass);

 private:
  std::vector<HashGrid<S>> grids_;
  std::vector<std::size_t> offsets_;
  int feature_dim_ = 0;
  std::size_t param_count_ = 0;
  AlignedVector<S> df_by_level_;   // [level][n][F]: dL/df level-major, so the scatter streams
  AlignedVector<S> beta_by_grid_;  // [grid][n]
  AlignedVector<S> group_dpos_;    // [group][n][3]
};

}  // namespace endorecon::field
