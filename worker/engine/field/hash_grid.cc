#include "worker/engine/field/hash_grid.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>

#include "common/error.h"
#include "worker/engine/base/counter_rng.h"
#include "worker/engine/field/hash_grid_simd.h"
#include "worker/engine/field/level_dispatch.h"

namespace endorecon::field {
namespace {

constexpr int kTile = 4096;  // samples per level walk: enough lookups to reuse a level's table from L2

// Asks for a level's table to be brought into L2 with sequential prefetches before `lookups` random
// reads of it: streaming the lines in is much faster than taking each one as a random miss. Skipped
// when the table is larger than L2 could hold or the reads are too few to touch most of its lines.
template <typename S>
void PrefetchTable(const S* table, std::size_t count, std::size_t lookups) {
  constexpr std::size_t kLine = 64, kMaxBytes = std::size_t{1} << 20;
  const std::size_t bytes = count * sizeof(S);
  if (bytes > kMaxBytes || lookups * kLine < bytes) return;
  const char* p = reinterpret_cast<const char*>(table);
  for (std::size_t b = 0; b < bytes; b += kLine) __builtin_prefetch(p + b, 0, 2);
}

}  // namespace

int LevelResolution(const HashGridConfig& config, int level) {
  const double r = std::floor(config.base_resolution * std::pow(config.scale, level) + 1e-9);
  return static_cast<int>(std::min(r, 1e9));
}

int LevelsUpToResolution(const HashGridConfig& config, double finest_useful) {
  int keep = 1;
  while (keep < config.levels && LevelResolution(config, keep) <= finest_useful) ++keep;
  return keep;
}

template <typename S>
HashGrid<S>::HashGrid(const HashGridConfig& config) : config_(config) {
  const int f = config.features;
  if (f != 1 && f != 2 && f != 4 && f != 8)
    FailInvalid("hash grid features per level must be 1, 2, 4 or 8, got " + std::to_string(f));
  if (config.log2_table < kLeastLog2Table || config.log2_table > kMostLog2Table) {
    FailInvalid("hash grid log2 table size must be in [" + std::to_string(kLeastLog2Table) + ", " +
                std::to_string(kMostLog2Table) + "], got " + std::to_string(config.log2_table));
  }
  if (config.levels < 1)
    FailInvalid("hash grid needs at least 1 level, got " + std::to_string(config.levels));
  if (config.base_resolution < 1)
    FailInvalid("hash grid base resolution must be >= 1, got " + std::to_string(config.base_resolution));
  if (!(config.scale >= 1))
    FailInvalid("hash grid per-level scale must be >= 1, got " + std::to_string(config.scale));
  const int keep =
      config.max_resolution > 0 ? LevelsUpToResolution(config, config.max_resolution) : config.levels;
  const std::uint64_t table = std::uint64_t{1} << config.log2_table;
  std::uint64_t offset = 0;
  for (int l = 0; l < keep; ++l) {
    GridLevel level;
    level.res = static_cast<std::uint32_t>(LevelResolution(config, l));
    const std::uint64_t side = std::uint64_t{level.res} + 1;
    const std::uint64_t vertices = side * side * side;
    level.dense = vertices <= table ? 1 : 0;
    // Each level starts on a 64-byte boundary for any F and scalar type.
    const std::uint64_t entries = level.dense ? (vertices + 7) / 8 * 8 : table;
    level.entries = static_cast<std::uint32_t>(level.dense ? vertices : table);
    level.offset = offset;
    offset += entries;
    levels_.push_back(level);
  }
  param_count_ = offset * f;
}

template <typename S>
void HashGrid<S>::Init(S* params, std::uint64_t seed) const {
  const base::CounterRng<S> rng(seed, 0x4a5347u);
  for (std::size_t i = 0; i < param_count_; ++i) {
    params[i] = S(1e-4) * (S(2) * rng(static_cast<std::uint32_t>(i)) - S(1));
  }
}

template <typename S>
void HashGrid<S>::ForwardRows(const S* params, const S* pos, int n, S* feat, int feat_stride) const {
  for (int begin = 0; begin < n; begin += kTile) {
    const int count = std::min(kTile, n - begin);
    for (int l = 0; l < levels(); ++l) {
      DispatchLevel(features(), levels_[l], [&](auto fc, auto dense) {
        constexpr int F = decltype(fc)::value;
        constexpr bool kDense = decltype(dense)::value;
        const S* table = params + levels_[l].offset * F;
        PrefetchTable(table, level_param_count(l), 8 * static_cast<std::size_t>(count));
        S* out = feat + static_cast<std::size_t>(begin) * feat_stride + l * F;
        int done = 0;
#ifdef ENDORECON_FIELD_AVX512
        if constexpr (F == 2 && std::is_same_v<S, float>) {
          done = count - count % simd::kBlock;
          simd::ForwardLevelF2<kDense>(levels_[l], table, pos + 3 * begin, done, out, feat_stride);
        }
#endif
        for (int i = done; i < count; ++i) {
          GatherLevel<F, kDense>(levels_[l], table, pos + 3 * static_cast<std::size_t>(begin + i),
                                 out + static_cast<std::size_t>(i) * feat_stride);
        }
      });
    }
  }
}

template <typename S>
void HashGrid<S>::BackwardLevel(int l, const S* pos, int n, const S* dfeat, int dfeat_stride, const S* scale,
                                S* grads, const S* params, S* dpos_add) const {
  const GridLevel& level = levels_[l];
  DispatchLevel(features(), level, [&](auto fc, auto dense) {
    constexpr int F = decltype(fc)::value;
    constexpr bool kDense = decltype(dense)::value;
    const std::size_t offset = level.offset * F;
    PrefetchTable(grads + offset, level_param_count(l), 8 * static_cast<std::size_t>(n));
    if (dpos_add) PrefetchTable(params + offset, level_param_count(l), 8 * static_cast<std::size_t>(n));
    auto run = [&](auto position) {
      constexpr bool kPosition = decltype(position)::value;
      const S* table = kPosition ? params + offset : nullptr;
      int done = 0;
#ifdef ENDORECON_FIELD_AVX512
      if constexpr (F == 2 && std::is_same_v<S, float>) {
        done = n - n % simd::kBlock;
        simd::ScatterLevelF2<kDense, kPosition>(level, pos, done, dfeat, dfeat_stride, scale, grads + offset,
                                                table, dpos_add);
      }
#endif
      for (int i = done; i < n; ++i) {
        const std::size_t r = static_cast<std::size_t>(i);
        ScatterLevel<F, kDense, kPosition>(level, pos + 3 * r, dfeat + r * dfeat_stride,
                                           scale ? scale[r] : S(1), grads + offset, table,
                                           kPosition ? dpos_add + 3 * r : nullptr, PlainAdd{});
      }
    };
    if (dpos_add) {
      run(std::true_type{});
    } else {
      run(std::false_type{});
    }
  });
}

template class HashGrid<float>;
template class HashGrid<double>;

}  // namespace endorecon::field
