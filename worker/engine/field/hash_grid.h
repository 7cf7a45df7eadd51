// One multi-resolution hash grid (instant-ngp): level l has floor(base * scale^l) cells per axis, a
// table of up to 2^log2_table slots of `features` values each, dense where the level's vertices fit,
// hashed otherwise; a position's feature at a level is the trilinear blend of its cell's 8 corners.
// The object holds the layout only; the table and its gradient are caller arrays (param_count()).
// Its loops are serial over the rows they are given: the trainable module is GridEnsemble (one or more
// grids), which owns the parallel loops, and the CUDA kernels run the same per-sample functions.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "worker/engine/field/hash_math.h"

namespace endorecon::field {

// A level's table holds 2^log2_table slots, log2_table in this range.
inline constexpr int kLeastLog2Table = 4;
inline constexpr int kMostLog2Table = 26;

struct HashGridConfig {
  int levels = 16;
  int features = 2;  // per level: 1, 2, 4 or 8
  int log2_table = 19;
  int base_resolution = 16;
  double scale = 1.5;      // per-level growth of the resolution
  int max_resolution = 0;  // 0: keep every level; otherwise levels finer than this are left out
};

// Cells per axis of level l (before any cap).
int LevelResolution(const HashGridConfig& config, int level);

// How many levels to keep when the finest resolution a scene can use is `finest_useful` cells per
// axis (e.g. the scene box over the smallest pixel footprint): the levels at or below it, at least 1.
int LevelsUpToResolution(const HashGridConfig& config, double finest_useful);

template <typename S>
class HashGrid {
 public:
  // Throws Error(kInvalidArgument) for a bad shape (features not 1/2/4/8, log2_table outside [4, 26],
  // base resolution < 1, scale < 1, levels < 1).
  explicit HashGrid(const HashGridConfig& config);

  const HashGridConfig& config() const { return config_; }
  int levels() const { return static_cast<int>(levels_.size()); }  // kept levels
  int dropped_levels() const { return config_.levels - levels(); }
  int features() const { return config_.features; }
  int output_dim() const { return levels() * features(); }
  const GridLevel& level(int l) const { return levels_[l]; }
  std::size_t param_count() const { return param_count_; }
  // Scalars of level l's table, starting at level(l).offset * features().
  std::size_t level_param_count(int l) const { return std::size_t{levels_[l].entries} * features(); }

  // Uniform in +-1e-4, as instant-ngp.
  void Init(S* params, std::uint64_t seed) const;

  // Features of n positions (n x 3, clamped into [0, 1]^3, NaN read as 0): row i of feat (at
  // feat + i * feat_stride) receives output_dim() values, level-major. Walks the levels one at a
  // time over tiles of samples so a level's table stays in cache.
  void ForwardRows(const S* params, const S* pos, int n, S* feat, int feat_stride) const;

  // Gradient of level l's table: grads[level slots] += scale_i * trilinear weights * dfeat_i, where
  // dfeat_i (F values) is at dfeat + i * dfeat_stride and scale_i = scale[i] (1 when scale is null).
  // Touches only level l's part of grads, so different levels may run on different threads. When
  // dpos_add is not null (params must be given then), also adds this level's part of dL/dpos (n x 3)
  // to it in the same pass (hash_math.h ScatterLevel).
  void BackwardLevel(int l, const S* pos, int n, const S* dfeat, int dfeat_stride, const S* scale, S* grads,
                     const S* params = nullptr, S* dpos_add = nullptr) const;

 private:
  HashGridConfig config_;
  std::vector<GridLevel> levels_;
  std::size_t param_count_ = 0;
};

}  // namespace endorecon::field
