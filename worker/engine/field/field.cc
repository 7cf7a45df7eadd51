#include "worker/engine/field/field.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <Eigen/Core>
#include <algorithm>
#include <array>
#include <cstring>
#include <istream>
#include <optional>
#include <ostream>
#include <sstream>

#include "common/error.h"
#include "worker/engine/field/frequency_encoding.h"
#include "worker/engine/field/temporal_blend.h"

namespace endorecon::field {
namespace {

constexpr int kTile = 512;    // samples per tile of the heads: a tile's activations stay in L1/L2
constexpr int kChunk = 2048;  // samples per chunk (task): the grids walk their levels over a chunk, so a
                              // level's table is pulled into L2 once and reused by ~16k lookups
constexpr int kPositionGroups = 4;  // fixed split of the grid levels for dL/dx0 (see ScatterTables)
constexpr int kMaxLayers = 8;       // hidden layers per head
constexpr char kMagic[16] = "ENDORECON-FIELD";
constexpr std::uint32_t kFormatVersion = 1;

// Every buffer starts on a cache line, so the vector kernels (Eigen's GEMMs) take the same path
// whatever addresses the allocator hands out: a fixed seed on one thread gives bit-equal results.
template <typename S>
using AlignedVector = std::vector<S, Eigen::aligned_allocator<S>>;

enum Group { kGrid, kBlend, kDeform, kDensity, kColor, kGroups };
constexpr std::array<const char*, kGroups> kGroupNames = {"grid", "blend", "deform", "density", "color"};

template <typename S>
void GrowTo(AlignedVector<S>& v, std::size_t size) {
  if (v.size() < size) v.resize(size);
}

// Runs fn(chunk, row0, rows) for the chunks of kChunk rows of a batch of n, in parallel.
// The split depends only on n, never on the thread count. Returns the number of chunks.
template <typename Fn>
int RunChunks(int n, Fn&& fn) {
  const int chunks = (n + kChunk - 1) / kChunk;
  tbb::parallel_for(tbb::blocked_range<int>(0, chunks, 1), [&](const tbb::blocked_range<int>& r) {
    for (int c = r.begin(); c != r.end(); ++c) fn(c, c * kChunk, std::min(kChunk, n - c * kChunk));
  });
  return chunks;
}

// Calls fn(offset, rows) for the tiles of kTile rows of a chunk of `rows` rows.
template <typename Fn>
void ForTiles(int rows, Fn&& fn) {
  for (int t = 0; t < rows; t += kTile) fn(t, std::min(kTile, rows - t));
}

template <typename S>
void CheckBatch(const SampleBatchT<S>& batch, const char* what) {
  if (batch.n < 0)
    FailInvalid(std::string(what) + ": batch size must be >= 0, got " + std::to_string(batch.n));
  if (batch.n > 0 && (!batch.pos || !batch.time || !batch.dir)) {
    FailInvalid(std::string(what) + ": the batch needs pos, time and dir arrays");
  }
}

template <typename S>
const S* Offset(const S* p, std::size_t k) {
  return p ? p + k : nullptr;
}

}  // namespace

FieldConfig FieldConfig::Paper() {
  FieldConfig c;
  c.grids.base_resolutions = {8, 16, 32};
  c.grids.scales = {1.4, 1.7, 1.9};
  c.grids.levels = 16;
  c.grids.features = 8;
  c.grids.log2_table = 19;
  c.deformation.resolution = 32;
  c.deformation.time_knots = 16;
  c.heads.density_hidden = {64};
  c.heads.color_hidden = {64, 64};
  return c;
}

// Sized on this machine kind (2 cores, AVX-512; bench/field_bench, 32768-sample batches): 3 grids x 10
// levels x 2 features reach resolutions ~550-660 (a pixel's footprint for clips up to ~640 wide), 2^14-slot
// tables (128 KiB per level, 3.5 MiB in all) stay in L2/L3 between steps (2^15 cost ~15% more), heads of
// 32 hidden units (2304 multiply-adds per sample) keep the MLPs near a third of the time. Forward +
// backward: ~2.4 M samples/s on 2 threads (~3.2 M without deformation); forward alone ~8.4 M.
FieldConfig FieldConfig::Cpu() {
  FieldConfig c;
  c.grids.base_resolutions = {8, 16, 32};
  c.grids.scales = {1.6, 1.5, 1.4};
  c.grids.levels = 10;
  c.grids.features = 2;
  c.grids.log2_table = 14;
  c.deformation.resolution = 16;
  c.deformation.time_knots = 8;
  c.heads.density_hidden = {32};
  c.heads.color_hidden = {32};
  return c;
}

// 0 for the hash encoding; the number of frequencies for the frequency encoding.
int EncodingFrequencies(const FieldConfig& config) {
  if (config.encoding == "hash") return 0;
  if (config.encoding != "frequency") {
    FailInvalid("field.encoding must be hash or frequency, got '" + config.encoding + "'");
  }
  if (config.frequencies < 1 || config.frequencies > 16) {
    FailInvalid("field.frequencies must be in [1, 16], got " + std::to_string(config.frequencies));
  }
  return config.frequencies;
}

template <typename S>
struct FieldT<S>::Impl {
  // Batch-major activations kept from Forward for Backward (a View points at one row of them). What is
  // cheap to recompute (the blend weights and blended features, the colour head's input) is not kept
  // but rebuilt per tile in Tile, so the batch-sized footprint stays small and the tables stay cached.
  struct Acts {
    AlignedVector<S> x0, gfeat, dens_raw, col_raw;
    std::array<AlignedVector<S>, kMaxLayers> dens_hidden, col_hidden;
  };
  struct View {
    S *x0, *gfeat, *dens_raw, *col_raw;
    S* dens_hidden[kMaxLayers];
    S* col_hidden[kMaxLayers];
  };
  struct Tile {  // per-tile temporaries
    AlignedVector<S> blend_hidden, beta, feat, col_in, temp;
  };
  struct Scratch {  // one per thread, reused across calls
    Acts chunk;     // Infer's activations (one chunk)
    Tile tile;
  };
  GridEnsemble<S> grids;
  TemporalBlend<S> blend;
  int frequencies;  // > 0: the frequency encoding replaces the grids and the blend (no parameters)
  std::optional<Deformation<S>> deform;
  DensityHead<S> density;
  ColorHead<S> color;

  std::array<AlignedVector<S>, kGroups> value, grad;
  Acts acts;         // kept activations of the last Forward
  int capacity = 0;  // rows `acts` holds
  tbb::enumerable_thread_specific<Scratch> scratch;
  std::vector<std::array<AlignedVector<S>, kGroups>>
      chunk_grad;                   // each chunk's share of the small groups' gradients
  AlignedVector<S> dfeat_by_level;  // [level][n][F]: dL/df, read by the table scatter
  AlignedVector<S> beta_by_grid;    // [grid][n]
  AlignedVector<S> group_dpos;      // [kPositionGroups][n][3]: parts of dL/dx0
  AlignedVector<S> dx0;             // n x 3: dL/dx0, read by the deformation scatter
  int last_n = -1;
  bool last_dropout = false;

  explicit Impl(const FieldConfig& config)
      : grids(config.grids),
        blend(grids.grids(), grids.feature_dim(), config.blend_hidden),
        frequencies(EncodingFrequencies(config)),
        density(frequencies > 0 ? FrequencyEncodingDim(frequencies) : grids.feature_dim(), config.heads),
        color(config.heads) {
    if (config.heads.density_hidden.size() > kMaxLayers || config.heads.color_hidden.size() > kMaxLayers) {
      FailInvalid("field heads may have at most " + std::to_string(kMaxLayers) + " hidden layers each");
    }
    if (config.deformation.enabled) deform.emplace(config.deformation);
    const bool hash = frequencies == 0;
    const std::array<std::size_t, kGroups> sizes = {
        hash ? grids.param_count() : 0, hash ? blend.param_count() : 0, deform ? deform->param_count() : 0,
        density.param_count(), color.param_count()};
    for (int g = 0; g < kGroups; ++g) {
      value[g].assign(sizes[g], S(0));
      grad[g].assign(sizes[g], S(0));
    }
  }

  // Per sample: what the encoder writes (all grids' features, or the frequency encoding), and what
  // the density head reads (the blended features, or the same frequency encoding).
  int encoder_dim() const { return frequencies > 0 ? FrequencyEncodingDim(frequencies) : grids.output_dim(); }
  int feature_dim() const {
    return frequencies > 0 ? FrequencyEncodingDim(frequencies) : grids.feature_dim();
  }

  void SizeActs(Acts& a, int rows) const {
    const std::size_t n = static_cast<std::size_t>(rows);
    GrowTo(a.x0, n * 3);
    GrowTo(a.gfeat, n * encoder_dim());
    GrowTo(a.dens_raw, n * density.raw_dim());
    GrowTo(a.col_raw, n * 4);
    for (int k = 0; k < density.mlp().hidden_layers(); ++k)
      GrowTo(a.dens_hidden[k], n * density.mlp().hidden_dim(k));
    for (int k = 0; k < color.mlp().hidden_layers(); ++k)
      GrowTo(a.col_hidden[k], n * color.mlp().hidden_dim(k));
  }

  View ViewAt(Acts& a, int row0) const {
    const std::size_t r = static_cast<std::size_t>(row0);
    View v{};
    v.x0 = a.x0.data() + r * 3;
    v.gfeat = a.gfeat.data() + r * encoder_dim();
    v.dens_raw = a.dens_raw.data() + r * density.raw_dim();
    v.col_raw = a.col_raw.data() + r * 4;
    for (int k = 0; k < density.mlp().hidden_layers(); ++k) {
      v.dens_hidden[k] = a.dens_hidden[k].data() + r * density.mlp().hidden_dim(k);
    }
    for (int k = 0; k < color.mlp().hidden_layers(); ++k) {
      v.col_hidden[k] = a.col_hidden[k].data() + r * color.mlp().hidden_dim(k);
    }
    return v;
  }

  Tile& LocalTile() {
    Tile& t = scratch.local().tile;
    const std::size_t n = kTile;
    GrowTo(t.blend_hidden, n * blend.hidden_dim());
    GrowTo(t.beta, n * grids.grids());
    GrowTo(t.feat, n * feature_dim());
    GrowTo(t.col_in, n * color.in_dim());
    // Backward: dL/dgeo, dL/df and the heads' scratch.
    const std::size_t heads =
        std::max({density.scratch_size(kTile), color.scratch_size(kTile), blend.scratch_size(kTile)});
    GrowTo(t.temp, n * (density.raw_dim() + feature_dim()) + heads);
    return t;
  }

  // Blend weights of `n` rows (time t) into tile t, and the blended grid features of view w into
  // feat (t.feat unless given).
  void BlendTile(const S* time, int n, const View& w, Tile& t, S* feat = nullptr) const {
    blend.Weights(value[kBlend].data(), time, n, t.blend_hidden.data(), t.beta.data());
    blend.Blend(t.beta.data(), w.gfeat, n, feat ? feat : t.feat.data());
  }

  // Deformation and grids of batch rows [row0, row0 + rows) (one chunk) into view v: the grids walk
  // their levels over the whole chunk.
  void GridsChunk(const SampleBatchT<S>& batch, const View& v, int row0, int rows) {
    const std::size_t r = static_cast<std::size_t>(row0);
    const S* x0 = batch.pos + 3 * r;
    if (deform) {
      deform->Forward(value[kDeform].data(), x0, batch.time + r, rows, v.x0);
      x0 = v.x0;
    }
    if (frequencies > 0) {
      for (int i = 0; i < rows; ++i) FrequencyEncode(x0 + 3 * i, frequencies, v.gfeat + i * encoder_dim());
    } else {
      grids.Forward(value[kGrid].data(), x0, rows, v.gfeat);
    }
  }

  // The density head's input for n rows of view w (time t): the blended grid features, written to
  // dst (t.feat when null), or the frequency encoding where it already is (copied to dst if given).
  const S* TileFeatures(const S* time, int n, const View& w, Tile& t, S* dst = nullptr) const {
    if (frequencies > 0) {
      if (dst != nullptr) std::copy(w.gfeat, w.gfeat + static_cast<std::size_t>(n) * encoder_dim(), dst);
      return dst != nullptr ? dst : w.gfeat;
    }
    BlendTile(time, n, w, t, dst);
    return dst != nullptr ? dst : t.feat.data();
  }

  // Both heads on n rows of blended features starting at batch row q (whose number keys the dropout
  // masks, so the same row gets the same mask whichever call evaluates it); activations into view w.
  void HeadsTile(const S* feat, const S* dir, std::size_t q, int n, const View& w, Tile& t,
                 const FieldOutputT<S>& out, bool dropout, std::uint64_t seed) {
    const DropoutPass drop{dropout, seed, static_cast<std::uint32_t>(q)};
    density.Forward(value[kDensity].data(), feat, n, w.dens_hidden, w.dens_raw, out.sigma + q,
                    out.sigma_logvar + q, drop);
    color.Forward(value[kColor].data(), w.dens_raw + 2, density.raw_dim(), dir + 3 * q, n, t.col_in.data(),
                  w.col_hidden, w.col_raw, out.rgb + 3 * q, out.rgb_logvar + q, drop);
  }

  // The whole field on batch rows [row0, row0 + rows) (one chunk), activations into rows
  // [a_row0, a_row0 + rows) of `a`; after the grids, tile by tile.
  void ForwardChunk(const SampleBatchT<S>& batch, const FieldOutputT<S>& out, Acts& a, int a_row0, int row0,
                    int rows, bool dropout, std::uint64_t seed) {
    GridsChunk(batch, ViewAt(a, a_row0), row0, rows);
    Tile& t = LocalTile();
    ForTiles(rows, [&](int t0, int n) {
      const View w = ViewAt(a, a_row0 + t0);
      const std::size_t q = static_cast<std::size_t>(row0 + t0);
      HeadsTile(TileFeatures(batch.time + q, n, w, t), batch.dir, q, n, w, t, out, dropout, seed);
    });
  }

  // Heads and blend of one chunk, tile by tile (rebuilding what Forward did not keep). Leaves dL/df
  // level-major and beta grid-major for the table scatter that follows.
  void BackwardChunk(const SampleBatchT<S>& batch, const FieldOutputGradT<S>& g, int c, int row0, int rows) {
    const int n = last_n;
    const int d = feature_dim(), f = grids.grid(0).features(), gn = grids.grids();
    auto& grads = chunk_grad[c];
    Tile& t = LocalTile();
    S* dgeo = t.temp.data();
    S* df = dgeo + static_cast<std::size_t>(kTile) * density.raw_dim();
    S* heads = df + static_cast<std::size_t>(kTile) * d;
    ForTiles(rows, [&](int t0, int rt) {
      const std::size_t q = static_cast<std::size_t>(row0 + t0);
      const View v = ViewAt(acts, row0 + t0);
      const S* feat = TileFeatures(batch.time + q, rt, v, t);
      color.Input(v.dens_raw + 2, density.raw_dim(), batch.dir + 3 * q, rt, t.col_in.data());
      color.Backward(value[kColor].data(), t.col_in.data(), rt, v.col_hidden, v.col_raw, Offset(g.rgb, 3 * q),
                     Offset(g.rgb_logvar, q), dgeo, grads[kColor].data(), heads, last_dropout);
      density.Backward(value[kDensity].data(), feat, rt, v.dens_hidden, v.dens_raw, Offset(g.sigma, q),
                       Offset(g.sigma_logvar, q), dgeo, df, grads[kDensity].data(), heads, last_dropout);
      if (frequencies > 0) {
        // No parameters: only dL/dx0, for the deformation.
        if (deform) {
          for (int i = 0; i < rt; ++i) {
            FrequencyEncodeBackward(v.x0 + 3 * i, frequencies, df + static_cast<std::size_t>(i) * d,
                                    dx0.data() + 3 * (q + i));
          }
        }
        return;
      }
      blend.Backward(value[kBlend].data(), batch.time + q, rt, t.blend_hidden.data(), t.beta.data(), v.gfeat,
                     df, nullptr, grads[kBlend].data(), heads);
      // Level-major dL/df and grid-major beta, level (grid) by level, so the writes stream.
      for (int l = 0; l < d / f; ++l) {
        S* dst = dfeat_by_level.data() + (static_cast<std::size_t>(l) * n + q) * f;
        for (int i = 0; i < rt; ++i) {
          for (int j = 0; j < f; ++j) dst[i * f + j] = df[static_cast<std::size_t>(i) * d + l * f + j];
        }
      }
      for (int k = 0; k < gn; ++k) {
        S* dst = beta_by_grid.data() + static_cast<std::size_t>(k) * n + q;
        for (int i = 0; i < rt; ++i) dst[i] = t.beta[i * gn + k];
      }
    });
  }

  // Table gradients, one (grid, level) per task, then (with deformation) the deformation's gradient,
  // one time slice per task. Tasks write disjoint parts of the gradients. With deformation the level
  // tasks also produce dL/dx0: they are dealt round-robin into kPositionGroups fixed groups, each run in
  // order and adding into its own n x 3 buffer, and the buffers are summed in order: the result does
  // not depend on the thread count.
  void ScatterTables(const SampleBatchT<S>& batch) {
    const std::size_t n = static_cast<std::size_t>(last_n);
    if (frequencies > 0) {  // dL/dx0 is already in dx0 (BackwardChunk)
      if (deform) ScatterDeformation(batch);
      return;
    }
    const int f = grids.grid(0).features();
    std::vector<std::pair<int, int>> tasks;  // (grid, level)
    for (int k = 0; k < grids.grids(); ++k) {
      for (int l = 0; l < grids.grid(k).levels(); ++l) tasks.emplace_back(k, l);
    }
    const S* x0 = deform ? acts.x0.data() : batch.pos;
    auto run = [&](std::size_t i, S* dpos) {
      const auto [k, l] = tasks[i];
      grids.BackwardLevel(k, l, x0, last_n, dfeat_by_level.data() + l * n * f, f, beta_by_grid.data() + k * n,
                          grad[kGrid].data(), dpos ? value[kGrid].data() : nullptr, dpos);
    };
    if (!deform) {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, tasks.size(), 1), [&](const auto& range) {
        for (std::size_t i = range.begin(); i != range.end(); ++i) run(i, nullptr);
      });
      return;
    }
    GrowTo(group_dpos, kPositionGroups * n * 3);
    tbb::parallel_for(0, kPositionGroups, [&](int group) {
      S* dpos = group_dpos.data() + group * n * 3;
      std::fill_n(dpos, n * 3, S(0));
      for (std::size_t i = group; i < tasks.size(); i += kPositionGroups) run(i, dpos);
    });
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n * 3, 4096), [&](const auto& range) {
      for (std::size_t j = range.begin(); j != range.end(); ++j) {
        S sum = S(0);
        for (int group = 0; group < kPositionGroups; ++group) sum += group_dpos[group * n * 3 + j];
        dx0[j] = sum;
      }
    });
    ScatterDeformation(batch);
  }

  // The deformation's gradient from dL/dx0, one time slice per task.
  void ScatterDeformation(const SampleBatchT<S>& batch) {
    tbb::parallel_for(1, deform->config().time_knots + 1, [&](int knot) {
      deform->BackwardKnot(knot, batch.pos, batch.time, last_n, dx0.data(), grad[kDeform].data());
    });
  }

  // grad[group] += the first `used` chunks' shares, summed in chunk order.
  void ReduceChunks(int used) {
    for (int g : {kBlend, kDensity, kColor}) {
      S* dst = grad[g].data();
      for (int c = 0; c < used; ++c) {
        const S* src = chunk_grad[c][g].data();
        for (std::size_t i = 0; i < grad[g].size(); ++i) dst[i] += src[i];
      }
    }
  }
};

template <typename S>
FieldT<S>::FieldT(const FieldConfig& config, std::uint64_t seed)
    : config_(config), impl_(std::make_unique<Impl>(config)) {
  Impl& m = *impl_;
  if (m.frequencies == 0) {
    m.grids.Init(m.value[kGrid].data(), seed);
    m.blend.Init(m.value[kBlend].data(), seed + 1);
  }
  if (m.deform) m.deform->Init(m.value[kDeform].data());
  m.density.Init(m.value[kDensity].data(), seed + 2);
  m.color.Init(m.value[kColor].data(), seed + 3);
}

template <typename S>
FieldT<S>::~FieldT() = default;

template <typename S>
void FieldT<S>::Forward(const SampleBatchT<S>& batch, FieldOutputT<S>& out, bool dropout,
                        std::uint64_t dropout_seed) {
  CheckBatch(batch, "Field::Forward");
  Impl& m = *impl_;
  if (batch.n > m.capacity) {
    m.SizeActs(m.acts, batch.n);
    m.capacity = batch.n;
  }
  m.last_n = batch.n;
  m.last_dropout = dropout;
  RunChunks(batch.n, [&](int, int row0, int rows) {
    m.ForwardChunk(batch, out, m.acts, row0, row0, rows, dropout, dropout_seed);
  });
}

template <typename S>
void FieldT<S>::Infer(const SampleBatchT<S>& batch, FieldOutputT<S>& out, bool dropout,
                      std::uint64_t dropout_seed) {
  CheckBatch(batch, "Field::Infer");
  Impl& m = *impl_;
  RunChunks(batch.n, [&](int, int row0, int rows) {
    auto& acts = m.scratch.local().chunk;
    m.SizeActs(acts, kChunk);
    m.ForwardChunk(batch, out, acts, 0, row0, rows, dropout, dropout_seed);
  });
}

template <typename S>
int FieldT<S>::encoding_dim() const {
  return impl_->feature_dim();
}

template <typename S>
void FieldT<S>::Encode(const SampleBatchT<S>& batch, S* encoding) {
  CheckBatch(batch, "Field::Encode");
  Impl& m = *impl_;
  const std::size_t d = static_cast<std::size_t>(m.feature_dim());
  RunChunks(batch.n, [&](int, int row0, int rows) {
    auto& acts = m.scratch.local().chunk;
    m.SizeActs(acts, kChunk);
    m.GridsChunk(batch, m.ViewAt(acts, 0), row0, rows);
    auto& t = m.LocalTile();
    ForTiles(rows, [&](int t0, int n) {
      const std::size_t q = static_cast<std::size_t>(row0 + t0);
      m.TileFeatures(batch.time + q, n, m.ViewAt(acts, t0), t, encoding + q * d);
    });
  });
}

template <typename S>
void FieldT<S>::Decode(const S* encoding, const SampleBatchT<S>& batch, FieldOutputT<S>& out, bool dropout,
                       std::uint64_t dropout_seed) {
  CheckBatch(batch, "Field::Decode");
  Impl& m = *impl_;
  const std::size_t d = static_cast<std::size_t>(m.feature_dim());
  RunChunks(batch.n, [&](int, int row0, int rows) {
    auto& acts = m.scratch.local().chunk;
    m.SizeActs(acts, kChunk);
    auto& t = m.LocalTile();
    ForTiles(rows, [&](int t0, int n) {
      const std::size_t q = static_cast<std::size_t>(row0 + t0);
      m.HeadsTile(encoding + q * d, batch.dir, q, n, m.ViewAt(acts, t0), t, out, dropout, dropout_seed);
    });
  });
}

template <typename S>
void FieldT<S>::Backward(const SampleBatchT<S>& batch, const FieldOutputGradT<S>& grad) {
  Impl& m = *impl_;
  if (batch.n != m.last_n) {
    Fail(ErrorCode::kFailedPrecondition, "Field::Backward: batch of " + std::to_string(batch.n) +
                                             " samples, but the last Forward had " +
                                             std::to_string(m.last_n));
  }
  const std::size_t n = static_cast<std::size_t>(batch.n);
  if (m.frequencies == 0) {
    GrowTo(m.dfeat_by_level, n * m.grids.feature_dim());
    GrowTo(m.beta_by_grid, n * m.grids.grids());
  }
  if (m.deform) GrowTo(m.dx0, n * 3);
  const int chunks = (batch.n + kChunk - 1) / kChunk;
  if (static_cast<int>(m.chunk_grad.size()) < chunks) m.chunk_grad.resize(chunks);
  for (int c = 0; c < chunks; ++c) {
    for (int g : {kBlend, kDensity, kColor}) m.chunk_grad[c][g].assign(m.grad[g].size(), S(0));
  }
  RunChunks(batch.n, [&](int c, int row0, int rows) { m.BackwardChunk(batch, grad, c, row0, rows); });
  m.ScatterTables(batch);
  m.ReduceChunks(chunks);
}

template <typename S>
void FieldT<S>::ZeroGrad() {
  for (auto& g : impl_->grad) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, g.size(), 1 << 16),
                      [&](const auto& r) { std::fill(g.begin() + r.begin(), g.begin() + r.end(), S(0)); });
  }
}

template <typename S>
std::vector<ParamBlock<S>> FieldT<S>::Blocks() {
  std::vector<ParamBlock<S>> blocks;
  for (int g = 0; g < kGroups; ++g) {
    if (impl_->value[g].empty()) continue;
    blocks.push_back({kGroupNames[g], impl_->value[g].data(), impl_->grad[g].data(), impl_->value[g].size()});
  }
  return blocks;
}

template <typename S>
std::vector<train::ParamGroup> FieldT<S>::Params() requires std::same_as<S, float> {
  std::vector<train::ParamGroup> groups;
  for (const auto& b : Blocks()) groups.push_back({b.name, b.value, b.grad, b.size});
  return groups;
}

template <typename S>
void FieldT<S>::Save(std::ostream& out) const {
  out.write(kMagic, sizeof(kMagic));
  const std::uint32_t header[3] = {kFormatVersion, static_cast<std::uint32_t>(sizeof(S)), kGroups};
  out.write(reinterpret_cast<const char*>(header), sizeof(header));
  for (int g = 0; g < kGroups; ++g) {
    const std::uint64_t size = impl_->value[g].size();
    out.write(reinterpret_cast<const char*>(&size), sizeof(size));
    out.write(reinterpret_cast<const char*>(impl_->value[g].data()),
              static_cast<std::streamsize>(size * sizeof(S)));
  }
}

template <typename S>
void FieldT<S>::Load(std::istream& in) {
  char magic[sizeof(kMagic)] = {};
  std::uint32_t header[3] = {};
  in.read(magic, sizeof(magic));
  in.read(reinterpret_cast<char*>(header), sizeof(header));
  if (!in || std::memcmp(magic, kMagic, sizeof(kMagic)) != 0)
    Fail(ErrorCode::kDataLoss, "field checkpoint: not a field state (bad header)");
  if (header[0] != kFormatVersion || header[1] != sizeof(S) || header[2] != kGroups) {
    Fail(ErrorCode::kDataLoss, "field checkpoint: format " + std::to_string(header[0]) + ", " +
                                   std::to_string(header[1]) + "-byte scalars, " + std::to_string(header[2]) +
                                   " groups; expected " + std::to_string(kFormatVersion) + ", " +
                                   std::to_string(sizeof(S)) + ", " + std::to_string(kGroups));
  }
  for (int g = 0; g < kGroups; ++g) {
    std::uint64_t size = 0;
    in.read(reinterpret_cast<char*>(&size), sizeof(size));
    if (!in)
      Fail(ErrorCode::kDataLoss,
           std::string("field checkpoint: truncated before group '") + kGroupNames[g] + "'");
    if (size != impl_->value[g].size()) {
      Fail(ErrorCode::kDataLoss, std::string("field checkpoint: group '") + kGroupNames[g] + "' holds " +
                                     std::to_string(size) + " values but this field has " +
                                     std::to_string(impl_->value[g].size()) + " (another configuration?)");
    }
    in.read(reinterpret_cast<char*>(impl_->value[g].data()), static_cast<std::streamsize>(size * sizeof(S)));
    if (!in)
      Fail(ErrorCode::kDataLoss,
           std::string("field checkpoint: truncated inside group '") + kGroupNames[g] + "'");
  }
}

template <typename S>
std::string FieldT<S>::Describe() const {
  const Impl& m = *impl_;
  std::ostringstream s;
  if (m.frequencies > 0) {
    s << "frequency encoding: " << m.frequencies << " frequencies, " << m.feature_dim()
      << " values (no hash grids, no temporal blend)\n";
  } else {
    s << "hash grids: " << m.grids.grids() << " x (" << config_.grids.features << " features/level, 2^"
      << config_.grids.log2_table << " slots), blended feature width " << m.grids.feature_dim() << "\n";
    for (int k = 0; k < m.grids.grids(); ++k) {
      const auto& grid = m.grids.grid(k);
      s << "  grid " << k << ": base " << grid.config().base_resolution << ", scale " << grid.config().scale
        << ", " << grid.levels() << " levels (resolution " << grid.level(0).res << ".."
        << grid.level(grid.levels() - 1).res;
      int dense = 0;
      for (int l = 0; l < grid.levels(); ++l) dense += static_cast<int>(grid.level(l).dense);
      s << ", " << dense << " dense)";
      if (grid.dropped_levels() > 0) {
        s << "; left out " << grid.dropped_levels() << " finer levels (above resolution cap "
          << config_.grids.max_resolution << ")";
      }
      s << "\n";
    }
    s << "temporal blend: 1 -> " << m.blend.hidden_dim() << " -> " << m.blend.grids() << " softmax\n";
  }
  if (m.deform) {
    s << "deformation: 4D grid " << config_.deformation.resolution << "^3 cells x "
      << config_.deformation.time_knots << " time knots\n";
  } else {
    s << "deformation: left out (static scene)\n";
  }
  auto widths = [](const Mlp<S>& mlp) {
    std::string w = std::to_string(mlp.in_dim());
    for (int k = 0; k < mlp.hidden_layers(); ++k) w += " -> " + std::to_string(mlp.hidden_dim(k));
    return w + " -> " + std::to_string(mlp.out_dim());
  };
  s << "density head: " << widths(m.density.mlp()) << ", colour head: " << widths(m.color.mlp())
    << ", dropout " << config_.heads.dropout;
  if (config_.heads.ColorDropout() != config_.heads.dropout)
    s << " (colour " << config_.heads.ColorDropout() << ")";
  s << "\n";
  s << "parameters:";
  for (int g = 0; g < kGroups; ++g) {
    if (!m.value[g].empty()) s << " " << kGroupNames[g] << " " << m.value[g].size();
  }
  return s.str();
}

template <typename S>
std::size_t FieldT<S>::head_macs_per_sample() const {
  return impl_->density.mlp().macs_per_sample() + impl_->color.mlp().macs_per_sample();
}

template class FieldT<float>;
template class FieldT<double>;

}  // namespace endorecon::field
