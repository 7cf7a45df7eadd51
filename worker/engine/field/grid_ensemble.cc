#include "worker/engine/field/grid_ensemble.h"

#include <algorithm>
#include <string>
#include <utility>

#include "common/error.h"

namespace endorecon::field {

static_assert(TrainableModule<GridEnsemble<float>, float>);

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
void GridEnsemble<S>::Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass&) {
  const int stride = output_dim(), g_count = grids(), d = feature_dim_;
  ParallelTasks(in.n, kTaskRows, [&](int, int row0, int rows) {
    const std::size_t r = static_cast<std::size_t>(row0);
    for (int g = 0; g < g_count; ++g) {
      S* base = out.feats + r * stride + g * d;
      grids_[g].ForwardRows(params + offsets_[g], in.pos + 3 * r, rows, base, stride);
      const int used = grids_[g].output_dim();
      if (used == d) continue;
      for (int s = 0; s < rows; ++s) {
        std::fill(base + static_cast<std::size_t>(s) * stride + used,
                  base + static_cast<std::size_t>(s) * stride + d, S(0));
      }
    }
    // The blend, while the task's features are still in cache.
    for (std::size_t s = r; s < r + static_cast<std::size_t>(rows); ++s) {
      const S* b = in.beta + s * g_count;
      const S* feats = out.feats + s * stride;
      S* f = out.f + s * d;
      for (int j = 0; j < d; ++j) f[j] = b[0] * feats[j];
      for (int g = 1; g < g_count; ++g) {
        for (int j = 0; j < d; ++j) f[j] += b[g] * feats[g * d + j];
      }
    }
  });
}

template <typename S>
void GridEnsemble<S>::Backward(const S* params, const Inputs& in, const Outputs& out, const OutputGrads& grad,
                               S* dparams, const InputGrads& din, const DropoutPass&) {
  constexpr int kPositionGroups = 4;
  const std::size_t n = static_cast<std::size_t>(in.n);
  const int f = grids_.front().features(), levels = feature_dim_ / f, g_count = grids(), d = feature_dim_;
  // dL/dbeta_g = df . H_g(x); dL/df level-major and beta grid-major, level by level, so the writes stream.
  GrowTo(df_by_level_, static_cast<std::size_t>(levels) * n * f);
  GrowTo(beta_by_grid_, static_cast<std::size_t>(g_count) * n);
  ParallelTasks(in.n, kTaskRows, [&](int, int row0, int rows) {
    const std::size_t r = static_cast<std::size_t>(row0);
    if (din.dbeta) {
      for (std::size_t s = r; s < r + static_cast<std::size_t>(rows); ++s) {
        const S* df = grad.df + s * d;
        const S* feats = out.feats + s * output_dim();
        for (int g = 0; g < g_count; ++g) {
          S dot = S(0);
          for (int j = 0; j < d; ++j) dot += df[j] * feats[g * d + j];
          din.dbeta[s * g_count + g] = dot;
        }
      }
    }
    for (int l = 0; l < levels; ++l) {
      S* dst = df_by_level_.data() + (static_cast<std::size_t>(l) * n + r) * f;
      const S* src = grad.df + r * d + l * f;
      for (int i = 0; i < rows; ++i) {
        for (int j = 0; j < f; ++j) dst[i * f + j] = src[static_cast<std::size_t>(i) * d + j];
      }
    }
    for (int g = 0; g < g_count; ++g) {
      S* dst = beta_by_grid_.data() + static_cast<std::size_t>(g) * n + r;
      for (int i = 0; i < rows; ++i) dst[i] = in.beta[(r + i) * g_count + g];
    }
  });
  std::vector<std::pair<int, int>> tasks;  // (grid, level)
  for (int g = 0; g < g_count; ++g) {
    for (int l = 0; l < grids_[g].levels(); ++l) tasks.emplace_back(g, l);
  }
  auto run = [&](std::size_t t, S* dpos) {
    const auto [g, l] = tasks[t];
    grids_[g].BackwardLevel(l, in.pos, in.n, df_by_level_.data() + l * n * f, f, beta_by_grid_.data() + g * n,
                            dparams + offsets_[g], dpos ? params + offsets_[g] : nullptr, dpos);
  };
  if (!din.dpos) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tasks.size(), 1), [&](const auto& range) {
      for (std::size_t t = range.begin(); t != range.end(); ++t) run(t, nullptr);
    });
    return;
  }
  GrowTo(group_dpos_, kPositionGroups * n * 3);
  tbb::parallel_for(0, kPositionGroups, [&](int group) {
    S* dpos = group_dpos_.data() + group * n * 3;
    std::fill_n(dpos, n * 3, S(0));
    for (std::size_t t = group; t < tasks.size(); t += kPositionGroups) run(t, dpos);
  });
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n * 3, 4096), [&](const auto& range) {
    for (std::size_t j = range.begin(); j != range.end(); ++j) {
      S sum = S(0);
      for (int group = 0; group < kPositionGroups; ++group) sum += group_dpos_[group * n * 3 + j];
      din.dpos[j] = sum;
    }
  });
}

template class GridEnsemble<float>;
template class GridEnsemble<double>;

}  // namespace endorecon::field
