#include "worker/engine/field/hash_grid.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <type_traits>

#include "common/error.h"
#include "worker/engine/field/hash_grid_simd.h"
#include "worker/engine/render/rng.h"

namespace endorecon::field {
namespace {

constexpr int kTile = 4096;  // samples per level walk: enough lookups to reuse a level's table from L2

template <int F, bool kDense, typename S>
void ForwardLevel(const GridLevel& level, const S* table, const S* pos, int n, S* feat, int feat_stride) {
  for (int i = 0; i < n; ++i) {
    std::uint32_t slot[8];
    S w[8], frac[3];
    CellCornersOf<kDense>(level, pos + 3 * i, slot, w, frac);
    BlendCorners<F>(table, slot, w, feat + static_cast<std::size_t>(i) * feat_stride);
  }
}

// Table scatter of one level; with kPosition also the level's position gradient (the corner values
// it needs sit in the cache lines the scatter touches anyway).
template <int F, bool kDense, bool kPosition, typename S>
void ScatterLevel(const GridLevel& level, const S* pos, int n, const S* dfeat, int dfeat_stride,
                  const S* scale, S* grads, const S* table, S* dpos) {
  const S res = static_cast<S>(level.res);
  for (int i = 0; i < n; ++i) {
    std::uint32_t slot[8];
    S w[8], frac[3];
    CellCornersOf<kDense>(level, pos + 3 * i, slot, w, frac);
    const S* d = dfeat + static_cast<std::size_t>(i) * dfeat_stride;
    const S s = scale ? scale[i] : S(1);
    S g[F];
    for (int f = 0; f < F; ++f) g[f] = s * d[f];
    S dot[8];
    for (int k = 0; k < 8; ++k) {
      S* gv = grads + std::size_t{slot[k]} * F;
      if constexpr (kPosition) {
        const S* v = table + std::size_t{slot[k]} * F;
        dot[k] = S(0);
        for (int f = 0; f < F; ++f) dot[k] += v[f] * g[f];
      }
      for (int f = 0; f < F; ++f) gv[f] += w[k] * g[f];
    }
    if constexpr (kPosition) {
      S grad[3];
      TrilinearGradient(dot, frac, grad);
      for (int a = 0; a < 3; ++a) {
        if (InsideUnit(pos[3 * i + a])) dpos[3 * i + a] += res * grad[a];
      }
    }
  }
}

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

// Calls fn(std::integral_constant<int, F>, std::bool_constant<dense>) for a level of the grid.
template <typename Fn>
void Dispatch(int features, const GridLevel& level, Fn&& fn) {
  auto with_f = [&](auto f) {
    if (level.dense) {
      fn(f, std::true_type{});
    } else {
      fn(f, std::false_type{});
    }
  };
  switch (features) {
    case 1:
      with_f(std::integral_constant<int, 1>{});
      break;
    case 2:
      with_f(std::integral_constant<int, 2>{});
      break;
    case 4:
      with_f(std::integral_constant<int, 4>{});
      break;
    default:
      with_f(std::integral_constant<int, 8>{});
      break;
  }
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
  if (config.log2_table < 4 || config.log2_table > 26) {
    FailInvalid("hash grid log2 table size must be in [4, 26], got " + std::to_string(config.log2_table));
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
  const render::CounterRng<S> rng(seed, 0x4a5347u);
  for (std::size_t i = 0; i < param_count_; ++i) {
    params[i] = S(1e-4) * (S(2) * rng(static_cast<std::uint32_t>(i)) - S(1));
  }
}

template <typename S>
void HashGrid<S>::Forward(const S* params, const S* pos, int n, S* feat, int feat_stride) const {
  const int f = features();
  for (int begin = 0; begin < n; begin += kTile) {
    const int count = std::min(kTile, n - begin);
    for (int l = 0; l < levels(); ++l) {
      Dispatch(f, levels_[l], [&](auto fc, auto dense) {
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
        ForwardLevel<F, kDense>(levels_[l], table, pos + 3 * (begin + done), count - done,
                                out + static_cast<std::size_t>(done) * feat_stride, feat_stride);
      });
    }
  }
}

template <typename S>
void HashGrid<S>::BackwardLevel(int l, const S* pos, int n, const S* dfeat, int dfeat_stride, const S* scale,
                                S* grads, const S* params, S* dpos_add) const {
  const int f = features();
  const std::size_t offset = levels_[l].offset * f;
  Dispatch(f, levels_[l], [&](auto fc, auto dense) {
    constexpr int F = decltype(fc)::value;
    constexpr bool kDense = decltype(dense)::value;
    const GridLevel& level = levels_[l];
    PrefetchTable(grads + offset, level_param_count(l), 8 * static_cast<std::size_t>(n));
    if (dpos_add) PrefetchTable(params + offset, level_param_count(l), 8 * static_cast<std::size_t>(n));
    auto run = [&](auto position, int begin, int count) {
      constexpr bool kPosition = decltype(position)::value;
      const S* d = dfeat + static_cast<std::size_t>(begin) * dfeat_stride;
      const S* s = scale ? scale + begin : nullptr;
      S* dp = kPosition ? dpos_add + 3 * static_cast<std::size_t>(begin) : nullptr;
      const S* table = kPosition ? params + offset : nullptr;
#ifdef ENDORECON_FIELD_AVX512
      if constexpr (F == 2 && std::is_same_v<S, float>) {
        const int simd_count = count - count % simd::kBlock;
        simd::ScatterLevelF2<kDense, kPosition>(level, pos + 3 * begin, simd_count, d, dfeat_stride, s,
                                                grads + offset, table, dp);
        begin += simd_count;
        count -= simd_count;
        d += static_cast<std::size_t>(simd_count) * dfeat_stride;
        s = s ? s + simd_count : nullptr;
        dp = dp ? dp + 3 * static_cast<std::size_t>(simd_count) : nullptr;
      }
#endif
      ScatterLevel<F, kDense, kPosition>(level, pos + 3 * begin, count, d, dfeat_stride, s, grads + offset,
                                         table, dp);
    };
    if (dpos_add) {
      run(std::true_type{}, 0, n);
    } else {
      run(std::false_type{}, 0, n);
    }
  });
}

template class HashGrid<float>;
template class HashGrid<double>;

}  // namespace endorecon::field
