#include "worker/engine/field/grid_ensemble.h"

#include <algorithm>
#include <string>

#include "common/error.h"

namespace endorecon::field {

HashGridConfig GridEnsembleConfig::Grid(int i) const {
  HashGridConfig grid;
  grid.levels = levels;
  grid.features = features;
  grid.log2_table = log2_table;
  grid.base_resolution = base_resolutions[i];
  grid.scale = scales[i];
  grid.max_resolution = max_resolution;
  return grid;
}

template <typename S>
GridEnsemble<S>::GridEnsemble(const GridEnsembleConfig& config) {
  if (config.base_resolutions.empty() || config.base_resolutions.size() != config.scales.size()) {
    FailInvalid("grid ensemble needs as many base resolutions as scales (and at least one), got " +
                std::to_string(config.base_resolutions.size()) + " and " +
                std::to_string(config.scales.size()));
  }
  for (std::size_t i = 0; i < config.scales.size(); ++i) {
    grids_.emplace_back(config.Grid(static_cast<int>(i)));
    offsets_.push_back(param_count_);
    param_count_ += grids_.back().param_count();
    feature_dim_ = std::max(feature_dim_, grids_.back().output_dim());
  }
}

template <typename S>
void GridEnsemble<S>::Init(S* params, std::uint64_t seed) const {
  for (int i = 0; i < grids(); ++i)
    grids_[i].Init(params + offsets_[i], seed + static_cast<std::uint64_t>(i));
}

template <typename S>
void GridEnsemble<S>::Forward(const S* params, const S* pos, int n, S* feats) const {
  const int stride = output_dim();
  for (int i = 0; i < grids(); ++i) {
    S* base = feats + i * feature_dim_;
    grids_[i].Forward(params + offsets_[i], pos, n, base, stride);
    const int used = grids_[i].output_dim();
    if (used == feature_dim_) continue;
    for (int s = 0; s < n; ++s)
      std::fill(base + static_cast<std::size_t>(s) * stride + used,
                base + static_cast<std::size_t>(s) * stride + feature_dim_, S(0));
  }
}

template <typename S>
void GridEnsemble<S>::BackwardLevel(int g, int l, const S* pos, int n, const S* dfeat, int dfeat_stride,
                                    const S* scale, S* grads, const S* params, S* dpos_add) const {
  grids_[g].BackwardLevel(l, pos, n, dfeat, dfeat_stride, scale, grads + offsets_[g],
                          params ? params + offsets_[g] : nullptr, dpos_add);
}

template class GridEnsemble<float>;
template class GridEnsemble<double>;

}  // namespace endorecon::field
