// The ensemble of hash grids the paper blends in time: G grids with their own base resolution and
// per-level scale, sharing levels, features per level and table size. Each grid's output is padded to
// the same width D = (most levels any grid keeps) x F, so the blend can sum them; a level a grid left
// out (above the resolution cap) reads as 0.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "worker/engine/field/hash_grid.h"

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
  // Throws Error(kInvalidArgument) when the two lists differ in length or are empty, or a grid is bad.
  explicit GridEnsemble(const GridEnsembleConfig& config);

  int grids() const { return static_cast<int>(grids_.size()); }
  const HashGrid<S>& grid(int i) const { return grids_[i]; }
  std::size_t grid_offset(int i) const { return offsets_[i]; }  // grid i's table within params
  int feature_dim() const { return feature_dim_; }              // D
  int output_dim() const { return grids() * feature_dim_; }     // G * D
  std::size_t param_count() const { return param_count_; }

  void Init(S* params, std::uint64_t seed) const;

  // feats: n rows of G * D values (row i at feats + i * G * D): grid 0's D values, then grid 1's, ...
  void Forward(const S* params, const S* pos, int n, S* feats) const;

  // Table gradient of level l of grid g, and optionally that level's part of dL/dpos (added to
  // dpos_add; see HashGrid::BackwardLevel). Distinct (g, l) touch disjoint parts of grads, so they may
  // run in parallel.
  void BackwardLevel(int g, int l, const S* pos, int n, const S* dfeat, int dfeat_stride, const S* scale,
                     S* grads, const S* params = nullptr, S* dpos_add = nullptr) const;

 private:
  std::vector<HashGrid<S>> grids_;
  std::vector<std::size_t> offsets_;
  int feature_dim_ = 0;
  std::size_t param_count_ = 0;
};

}  // namespace endorecon::field
