#include "worker/engine/field/field.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <array>
#include <optional>
#include <string>

#include "common/error.h"
#include "worker/engine/field/batch_loop.h"

namespace endorecon::field {
namespace {

enum Group { kGrid, kBlend, kDeform, kDensity, kColor, kExposure, kBackground, kGroups };
constexpr const auto& kGroupNames = kParameterGroups;
static_assert(kGroupNames.size() == kGroups);

template <typename S>
void CheckBatch(const SampleBatchT<S>& batch, const char* what) {
  if (batch.n < 0)
    FailInvalid(std::string(what) + ": batch size must be >= 0, got " + std::to_string(batch.n));
  if (batch.n > 0 && (!batch.pos || !batch.time || !batch.dir)) {
    FailInvalid(std::string(what) + ": the batch needs pos, time and dir arrays");
  }
}

// Checks the whole configuration, naming its keys, before any module is built.
bool UsesFrequencyEncoding(const FieldConfig& config) {
  CheckFieldConfig(config);
  return config.encoding == "frequency";
}

}  // namespace

template <typename S>
struct FieldT<S>::Impl {
  // Batch-major activations of a pass over `rows` samples: Forward keeps the whole batch's for
  // Backward; Infer, Encode and Decode use one segment's per thread.
  struct Acts {
    AlignedVector<S> time, x0, gfeat, blend_hidden, beta, feat, dens_raw, col_in, col_raw, rgb0;
    std::array<AlignedVector<S>, kMaxHiddenLayers> dens_hidden, col_hidden;
    int rows = 0;
  };
  // Acts from one row on.
  struct View {
    S *time, *x0, *gfeat, *blend_hidden, *beta, *feat, *dens_raw, *col_in, *col_raw, *rgb0;
    std::array<S*, kMaxHiddenLayers> dens_hidden, col_hidden;
  };

  std::optional<GridEnsemble<S>> grids;
  std::optional<TemporalBlend<S>> blend;
  std::optional<FrequencyEncoder<S>> frequency;
  std::optional<Deformation<S>> deform;
  DensityHead<S> density;
  ColorHead<S> color;
  std::optional<Exposure<S>> exposure;
  std::optional<Background<S>> background;

  std::array<AlignedVector<S>, kGroups> value, grad;
  Acts acts;                                       // Forward's, kept for Backward
  tbb::enumerable_thread_specific<Acts> segments;  // Infer's, Encode's and Decode's
  AlignedVector<S> dgeo, dfeat, dbeta, dx0, drgb0;
  int last_n = -1;
  DropoutPass last_pass;
  // FieldConfig::trained_times; `clamps` when they are narrower than [0, 1].
  S first_time, last_time;
  bool clamps;

  Impl(const FieldConfig& config, bool frequency_encoding)
      : density(frequency_encoding ? FrequencyEncoder<S>(config.frequencies).output_dim()
                                   : GridEnsemble<S>(config.grids).feature_dim(),
                config.heads),
        color(config.heads),
        first_time(config.trained_times[0]),
        last_time(config.trained_times[1]),
        clamps(first_time > S(0) || last_time < S(1)) {
    if (frequency_encoding) {
      frequency.emplace(config.frequencies);
    } else {
      grids.emplace(config.grids);
      blend.emplace(grids->grids(), config.blend_hidden);
    }
    if (config.deformation.enabled) deform.emplace(config.deformation);
    if (!config.exposure_times.empty()) exposure.emplace(config.exposure_times);
    if (config.learned_background) background.emplace();
    const std::array<std::size_t, kGroups> sizes = {grids ? grids->param_count() : 0,
                                                    blend ? blend->param_count() : 0,
                                                    deform ? deform->param_count() : 0,
                                                    density.param_count(),
                                                    color.param_count(),
                                                    exposure ? exposure->param_count() : 0,
                                                    background ? background->param_count() : 0};
    for (int g = 0; g < kGroups; ++g) {
      value[g].assign(sizes[g], S(0));
      grad[g].assign(sizes[g], S(0));
    }
  }

  int feature_dim() const { return frequency ? frequency->output_dim() : grids->feature_dim(); }

  void Size(Acts& a, int rows) const {
    if (rows <= a.rows) return;
    a.rows = rows;
    const std::size_t n = static_cast<std::size_t>(rows);
    if (clamps) GrowTo(a.time, n);
    if (deform) GrowTo(a.x0, n * 3);
    if (grids) {
      GrowTo(a.gfeat, n * grids->output_dim());
      GrowTo(a.blend_hidden, n * blend->hidden_dim());
      GrowTo(a.beta, n * grids->grids());
    }
    GrowTo(a.feat, n * feature_dim());
    GrowTo(a.dens_raw, n * density.raw_dim());
    GrowTo(a.col_in, n * color.in_dim());
    GrowTo(a.col_raw, n * 4);
    if (exposure) GrowTo(a.rgb0, n * 3);
    for (int k = 0; k < density.mlp().hidden_layers(); ++k)
      GrowTo(a.dens_hidden[k], n * density.mlp().hidden_dim(k));
    for (int k = 0; k < color.mlp().hidden_layers(); ++k)
      GrowTo(a.col_hidden[k], n * color.mlp().hidden_dim(k));
  }

  View ViewAt(Acts& a, std::size_t r) const {
    const auto at = [r](AlignedVector<S>& v, std::size_t width) {
      return v.empty() ? nullptr : v.data() + r * width;
    };
    View v{};
    v.time = at(a.time, 1);
    v.x0 = at(a.x0, 3);
    v.gfeat = grids ? at(a.gfeat, grids->output_dim()) : nullptr;
    v.blend_hidden = blend ? at(a.blend_hidden, blend->hidden_dim()) : nullptr;
    v.beta = grids ? at(a.beta, grids->grids()) : nullptr;
    v.feat = at(a.feat, feature_dim());
    v.dens_raw = at(a.dens_raw, density.raw_dim());
    v.col_in = at(a.col_in, color.in_dim());
    v.col_raw = at(a.col_raw, 4);
    v.rgb0 = at(a.rgb0, 3);
    for (int k = 0; k < density.mlp().hidden_layers(); ++k)
      v.dens_hidden[k] = at(a.dens_hidden[k], density.mlp().hidden_dim(k));
    for (int k = 0; k < color.mlp().hidden_layers(); ++k)
      v.col_hidden[k] = at(a.col_hidden[k], color.mlp().hidden_dim(k));
    return v;
  }

  // The times the structure (deformation, blend, the colour head's time features) sees for rows
  // [q, q + rows) of the batch: the batch's, or held inside the trained times (v.time from row q).
  const S* StructureTimes(const SampleBatchT<S>& batch, std::size_t q, int rows, const View& v) const {
    if (!clamps) return batch.time + q;
    for (int i = 0; i < rows; ++i)
      v.time[i] = std::clamp(batch.time[q + std::size_t(i)], first_time, last_time);
    return v.time;
  }

  // Deformation, blend weights and grids (or the frequency encoding): rows [q, q + rows) of the batch,
  // activations in v, features into feat (rows x feature_dim()).
  void EncodeRows(const SampleBatchT<S>& batch, std::size_t q, int rows, const View& v, S* feat) {
    const S* pos = batch.pos + 3 * q;
    const S* time = StructureTimes(batch, q, rows, v);
    const S* x0 = pos;
    if (deform) {
      deform->Forward(value[kDeform].data(), {rows, pos, time}, {v.x0}, {});
      x0 = v.x0;
    }
    if (frequency) {
      frequency->Forward(nullptr, {rows, x0}, {feat}, {});
      return;
    }
    blend->Forward(value[kBlend].data(), {rows, time}, {v.blend_hidden, v.beta}, {});
    grids->Forward(value[kGrid].data(), {rows, x0, v.beta}, {v.gfeat, feat}, {});
  }

  // The heads: rows [q, q + rows) of the batch from their features into out, a tile at a time so a
  // tile's activations stay in cache between the two heads.
  void DecodeRows(const S* feat, const SampleBatchT<S>& batch, std::size_t q, int rows, const View& v,
                  const FieldOutputT<S>& out, DropoutPass pass) {
    const std::size_t d = static_cast<std::size_t>(feature_dim()),
                      raw = static_cast<std::size_t>(density.raw_dim());
    const S* time = out.rgb ? StructureTimes(batch, q, rows, v) : nullptr;  // row q on; the colour's
    ForTiles(rows, [&](int t0, int n) {
      const std::size_t t = static_cast<std::size_t>(t0), r = q + t;
      std::array<S*, kMaxHiddenLayers> dens_hidden{}, col_hidden{};
      for (int k = 0; k < density.mlp().hidden_layers(); ++k)
        dens_hidden[k] = v.dens_hidden[k] + t * density.mlp().hidden_dim(k);
      for (int k = 0; k < color.mlp().hidden_layers(); ++k)
        col_hidden[k] = v.col_hidden[k] + t * color.mlp().hidden_dim(k);
      pass.first_row = static_cast<std::uint32_t>(r);
      S* dens_raw = v.dens_raw + t * raw;
      density.Forward(value[kDensity].data(), {n, feat + t * d},
                      {dens_hidden.data(), dens_raw, out.sigma + r, out.sigma_logvar + r}, pass);
      if (!out.rgb) return;  // the density alone (Infer and Decode only)
      // With exposure the colour head writes the tissue's colour, which the camera's gains then scale.
      S* rgb = exposure ? v.rgb0 + 3 * t : out.rgb + 3 * r;
      color.Forward(
          value[kColor].data(), {n, dens_raw + 2, density.raw_dim(), batch.dir + 3 * r, time + t},
          {v.col_in + t * color.in_dim(), col_hidden.data(), v.col_raw + 4 * t, rgb, out.rgb_logvar + r},
          pass);
      if (exposure)
        exposure->Forward(value[kExposure].data(), {n, batch.time + r, rgb}, {out.rgb + 3 * r}, pass);
    });
  }

  // fn(q, rows, view) over the segments of kTaskRows rows of a batch of n, in parallel, each with its
  // thread's activations (the split depends on n only: results do not depend on the thread count).
  // A segment runs nested parallel loops (the blend's tiles); a thread waiting for them may be handed
  // other work, and were that another segment it would take the same thread's activations and
  // overwrite the waiting segment's (whole segments came out wrong on a 16-core machine). Isolation
  // keeps the waiting thread to its own segment's nested work.
  template <typename Fn>
  void ForSegments(int n, Fn&& fn) {
    ParallelTasks(n, kTaskRows, [&](int, int row0, int rows) {
      tbb::this_task_arena::isolate([&] {
        Acts& a = segments.local();
        Size(a, kTaskRows);
        fn(static_cast<std::size_t>(row0), rows, ViewAt(a, 0));
      });
    });
  }
};

template <typename S>
FieldT<S>::FieldT(const FieldConfig& config, std::uint64_t seed)
    : config_(config), impl_(std::make_unique<Impl>(config, UsesFrequencyEncoding(config))) {
  Impl& m = *impl_;
  if (m.grids) m.grids->Init(m.value[kGrid].data(), seed);
  if (m.blend) m.blend->Init(m.value[kBlend].data(), seed + 1);
  if (m.deform) m.deform->Init(m.value[kDeform].data(), seed);
  m.density.Init(m.value[kDensity].data(), seed + 2);
  m.color.Init(m.value[kColor].data(), seed + 3);
  if (m.exposure) m.exposure->Init(m.value[kExposure].data(), seed + 4);
  if (m.background) m.background->Init(m.value[kBackground].data(), seed + 5);
}

template <typename S>
FieldT<S>::~FieldT() = default;

template <typename S>
void FieldT<S>::Forward(const SampleBatchT<S>& batch, FieldOutputT<S>& out, bool dropout,
                        std::uint64_t dropout_seed) {
  CheckBatch(batch, "Field::Forward");
  if (batch.n > 0 && !out.rgb)
    FailInvalid("Field::Forward: the output needs its rgb array (Backward uses it)");
  Impl& m = *impl_;
  m.Size(m.acts, batch.n);
  m.last_n = batch.n;
  m.last_pass = {dropout, dropout_seed, 0};
  // Segment by segment as Infer (the same rows meet the same tiles), into the batch-sized activations.
  ParallelTasks(batch.n, kTaskRows, [&](int, int row0, int rows) {
    const std::size_t q = static_cast<std::size_t>(row0);
    const auto v = m.ViewAt(m.acts, q);
    m.EncodeRows(batch, q, rows, v, v.feat);
    m.DecodeRows(v.feat, batch, q, rows, v, out, m.last_pass);
  });
}

template <typename S>
void FieldT<S>::Infer(const SampleBatchT<S>& batch, FieldOutputT<S>& out, bool dropout,
                      std::uint64_t dropout_seed) {
  CheckBatch(batch, "Field::Infer");
  Impl& m = *impl_;
  m.ForSegments(batch.n, [&](std::size_t q, int rows, const auto& v) {
    m.EncodeRows(batch, q, rows, v, v.feat);
    m.DecodeRows(v.feat, batch, q, rows, v, out, {dropout, dropout_seed, 0});
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
  m.ForSegments(batch.n, [&](std::size_t q, int rows, const auto& v) {
    m.EncodeRows(batch, q, rows, v, encoding + q * d);
  });
}

template <typename S>
void FieldT<S>::Decode(const S* encoding, const SampleBatchT<S>& batch, FieldOutputT<S>& out, bool dropout,
                       std::uint64_t dropout_seed) {
  CheckBatch(batch, "Field::Decode");
  Impl& m = *impl_;
  const std::size_t d = static_cast<std::size_t>(m.feature_dim());
  m.ForSegments(batch.n, [&](std::size_t q, int rows, const auto& v) {
    m.DecodeRows(encoding + q * d, batch, q, rows, v, out, {dropout, dropout_seed, 0});
  });
}

template <typename S>
void FieldT<S>::Backward(const SampleBatchT<S>& batch, const FieldOutputGradT<S>& g) {
  Impl& m = *impl_;
  if (batch.n != m.last_n) {
    Fail(ErrorCode::kFailedPrecondition, "Field::Backward: batch of " + std::to_string(batch.n) +
                                             " samples, but the last Forward had " +
                                             std::to_string(m.last_n));
  }
  const int n = batch.n;
  const std::size_t rows = static_cast<std::size_t>(n);
  const auto a = m.ViewAt(m.acts, 0);
  const DropoutPass& pass = m.last_pass;
  const S* time = m.clamps ? a.time : batch.time;  // as Forward gave the structure
  GrowTo(m.dgeo, rows * std::size_t(config_.heads.geo_features));
  GrowTo(m.dfeat, rows * m.feature_dim());
  const S* drgb = g.rgb;
  if (m.exposure && g.rgb) {
    GrowTo(m.drgb0, rows * 3);
    m.exposure->Backward(m.value[kExposure].data(), {n, batch.time, a.rgb0}, {}, {g.rgb},
                         m.grad[kExposure].data(), {m.drgb0.data()}, pass);
    drgb = m.drgb0.data();
  }
  m.color.Backward(m.value[kColor].data(), {n, a.dens_raw + 2, m.density.raw_dim(), batch.dir, time},
                   {a.col_in, a.col_hidden.data(), a.col_raw, nullptr, nullptr}, {drgb, g.rgb_logvar},
                   m.grad[kColor].data(), {m.dgeo.data()}, pass);
  m.density.Backward(
      m.value[kDensity].data(), {n, a.feat}, {a.dens_hidden.data(), a.dens_raw, nullptr, nullptr},
      {g.sigma, g.sigma_logvar, m.dgeo.data()}, m.grad[kDensity].data(), {m.dfeat.data()}, pass);
  const S* x0 = m.deform ? a.x0 : batch.pos;
  if (m.deform) GrowTo(m.dx0, rows * 3);
  S* dx0 = m.deform ? m.dx0.data() : nullptr;
  if (m.frequency) {
    m.frequency->Backward(nullptr, {n, x0}, {a.feat}, {m.dfeat.data()}, nullptr, {dx0}, {});
  } else {
    GrowTo(m.dbeta, rows * m.grids->grids());
    m.grids->Backward(m.value[kGrid].data(), {n, x0, a.beta}, {a.gfeat, a.feat}, {m.dfeat.data()},
                      m.grad[kGrid].data(), {dx0, m.dbeta.data()}, {});
    m.blend->Backward(m.value[kBlend].data(), {n, time}, {a.blend_hidden, a.beta}, {m.dbeta.data()},
                      m.grad[kBlend].data(), {}, {});
  }
  if (m.deform) {
    m.deform->Backward(m.value[kDeform].data(), {n, batch.pos, time}, {a.x0}, {dx0}, m.grad[kDeform].data(),
                       {}, {});
  }
}

template <typename S>
void FieldT<S>::BackgroundRgb(int n, const S* dir, S* rgb) {
  Impl& m = *impl_;
  if (!m.background)
    Fail(ErrorCode::kFailedPrecondition, "Field::BackgroundRgb: the field has no background");
  m.background->Forward(m.value[kBackground].data(), {n, dir}, {rgb}, {});
}

template <typename S>
void FieldT<S>::BackgroundBackward(int n, const S* dir, const S* rgb, const S* drgb) {
  Impl& m = *impl_;
  if (!m.background)
    Fail(ErrorCode::kFailedPrecondition, "Field::BackgroundBackward: the field has no background");
  m.background->Backward(m.value[kBackground].data(), {n, dir}, {const_cast<S*>(rgb)}, {drgb},
                         m.grad[kBackground].data(), {}, {});
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
std::vector<ParamBlock<const S>> FieldT<S>::Blocks() const {
  std::vector<ParamBlock<const S>> blocks;
  for (int g = 0; g < kGroups; ++g) {
    if (impl_->value[g].empty()) continue;
    blocks.push_back({kGroupNames[g], impl_->value[g].data(), impl_->grad[g].data(), impl_->value[g].size()});
  }
  return blocks;
}

template <typename S>
const GridEnsemble<S>* FieldT<S>::grids() const {
  return impl_->grids ? &*impl_->grids : nullptr;
}

template <typename S>
const TemporalBlend<S>* FieldT<S>::blend() const {
  return impl_->blend ? &*impl_->blend : nullptr;
}

template <typename S>
const FrequencyEncoder<S>* FieldT<S>::frequency() const {
  return impl_->frequency ? &*impl_->frequency : nullptr;
}

template <typename S>
const Deformation<S>* FieldT<S>::deformation() const {
  return impl_->deform ? &*impl_->deform : nullptr;
}

template <typename S>
const DensityHead<S>& FieldT<S>::density() const {
  return impl_->density;
}

template <typename S>
const ColorHead<S>& FieldT<S>::color() const {
  return impl_->color;
}

template <typename S>
const Exposure<S>* FieldT<S>::exposure() const {
  return impl_->exposure ? &*impl_->exposure : nullptr;
}

template <typename S>
const Background<S>* FieldT<S>::background() const {
  return impl_->background ? &*impl_->background : nullptr;
}

template <typename S>
std::size_t FieldT<S>::head_macs_per_sample() const {
  return impl_->density.mlp().macs_per_sample() + impl_->color.mlp().macs_per_sample();
}

template class FieldT<float>;
template class FieldT<double>;

}  // namespace endorecon::field
