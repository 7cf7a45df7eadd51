#include "worker/engine/field/field.h"

#include <tbb/blocked_range.h>
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

enum Group { kGrid, kBlend, kDeform, kDensity, kColor, kGroups };
constexpr std::array<const char*, kGroups> kGroupNames = {"grid", "blend", "deform", "density", "color"};

template <typename S>
void CheckBatch(const SampleBatchT<S>& batch, const char* what) {
  if (batch.n < 0)
    FailInvalid(std::string(what) + ": batch size must be >= 0, got " + std::to_string(batch.n));
  if (batch.n > 0 && (!batch.pos || !batch.time || !batch.dir)) {
    FailInvalid(std::string(what) + ": the batch needs pos, time and dir arrays");
  }
}

bool UsesFrequencyEncoding(const FieldConfig& config) {
  if (config.encoding != "hash" && config.encoding != "frequency") {
    FailInvalid("field.encoding must be hash or frequency, got '" + config.encoding + "'");
  }
  return config.encoding == "frequency";
}

// Rows of one segment of Infer, Encode and Decode: a multiple of kTaskRows (so the modules' tiles and
// vector blocks fall on the same rows as in Forward, which keeps the results bit-equal), large enough
// to give every thread of the arena work.
int SegmentRows() { return kTaskRows * std::max(4, 2 * tbb::this_task_arena::max_concurrency()); }

}  // namespace

template <typename S>
struct FieldT<S>::Impl {
  // Batch-major activations of one pass over `rows` samples.
  struct Acts {
    AlignedVector<S> x0, gfeat, blend_hidden, beta, feat, dens_raw, col_in, col_raw;
    std::vector<AlignedVector<S>> dens_hidden, col_hidden;
    std::vector<S*> dens_hidden_ptr, col_hidden_ptr;
    int rows = 0;
  };

  std::optional<GridEnsemble<S>> grids;
  std::optional<TemporalBlend<S>> blend;
  std::optional<FrequencyEncoder<S>> frequency;
  std::optional<Deformation<S>> deform;
  DensityHead<S> density;
  ColorHead<S> color;

  std::array<AlignedVector<S>, kGroups> value, grad;
  Acts acts;     // Forward's, kept for Backward
  Acts segment;  // Infer's, Encode's and Decode's
  AlignedVector<S> dgeo, dfeat, dfeats, dx0;
  int last_n = -1;
  DropoutPass last_pass;

  Impl(const FieldConfig& config, bool frequency_encoding)
      : density(frequency_encoding ? FrequencyEncoder<S>(config.frequencies).output_dim()
                                   : GridEnsemble<S>(config.grids).feature_dim(),
                config.heads),
        color(config.heads) {
    if (frequency_encoding) {
      frequency.emplace(config.frequencies);
    } else {
      grids.emplace(config.grids);
      blend.emplace(grids->grids(), grids->feature_dim(), config.blend_hidden);
    }
    if (config.deformation.enabled) deform.emplace(config.deformation);
    const std::array<std::size_t, kGroups> sizes = {
        grids ? grids->param_count() : 0, blend ? blend->param_count() : 0,
        deform ? deform->param_count() : 0, density.param_count(), color.param_count()};
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
    const auto hidden = [n](const Mlp<S>& mlp, std::vector<AlignedVector<S>>& layers, std::vector<S*>& ptr) {
      layers.resize(mlp.hidden_layers());
      ptr.resize(mlp.hidden_layers());
      for (int k = 0; k < mlp.hidden_layers(); ++k) {
        GrowTo(layers[k], n * mlp.hidden_dim(k));
        ptr[k] = layers[k].data();
      }
    };
    hidden(density.mlp(), a.dens_hidden, a.dens_hidden_ptr);
    hidden(color.mlp(), a.col_hidden, a.col_hidden_ptr);
  }

  // Deformation, then the encoder: rows [q, q + rows) of the batch into feat (rows x feature_dim()).
  void EncodeRows(const SampleBatchT<S>& batch, std::size_t q, int rows, Acts& a, S* feat) {
    const S* pos = batch.pos + 3 * q;
    const S* time = batch.time + q;
    const S* x0 = pos;
    if (deform) {
      deform->Forward(value[kDeform].data(), {rows, pos, time}, {a.x0.data()}, {});
      x0 = a.x0.data();
    }
    if (frequency) {
      frequency->Forward(nullptr, {rows, x0}, {feat}, {});
      return;
    }
    grids->Forward(value[kGrid].data(), {rows, x0}, {a.gfeat.data()}, {});
    blend->Forward(value[kBlend].data(), {rows, time, a.gfeat.data()},
                   {a.blend_hidden.data(), a.beta.data(), feat}, {});
  }

  // The heads: rows [q, q + rows) of the batch from their features into out.
  void DecodeRows(const S* feat, const SampleBatchT<S>& batch, std::size_t q, int rows, Acts& a,
                  const FieldOutputT<S>& out, DropoutPass pass) {
    pass.first_row = static_cast<std::uint32_t>(q);
    density.Forward(value[kDensity].data(), {rows, feat},
                    {a.dens_hidden_ptr.data(), a.dens_raw.data(), out.sigma + q, out.sigma_logvar + q}, pass);
    color.Forward(
        value[kColor].data(), {rows, a.dens_raw.data() + 2, density.raw_dim(), batch.dir + 3 * q},
        {a.col_in.data(), a.col_hidden_ptr.data(), a.col_raw.data(), out.rgb + 3 * q, out.rgb_logvar + q},
        pass);
  }

  // fn(q, rows) for the segments of a batch of n, in order.
  template <typename Fn>
  void ForSegments(int n, Fn&& fn) {
    const int rows = SegmentRows();
    Size(segment, std::min(n, rows));
    for (int q = 0; q < n; q += rows) fn(static_cast<std::size_t>(q), std::min(rows, n - q));
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
}

template <typename S>
FieldT<S>::~FieldT() = default;

template <typename S>
void FieldT<S>::Forward(const SampleBatchT<S>& batch, FieldOutputT<S>& out, bool dropout,
                        std::uint64_t dropout_seed) {
  CheckBatch(batch, "Field::Forward");
  Impl& m = *impl_;
  m.Size(m.acts, batch.n);
  m.last_n = batch.n;
  m.last_pass = {dropout, dropout_seed, 0};
  m.EncodeRows(batch, 0, batch.n, m.acts, m.acts.feat.data());
  m.DecodeRows(m.acts.feat.data(), batch, 0, batch.n, m.acts, out, m.last_pass);
}

template <typename S>
void FieldT<S>::Infer(const SampleBatchT<S>& batch, FieldOutputT<S>& out, bool dropout,
                      std::uint64_t dropout_seed) {
  CheckBatch(batch, "Field::Infer");
  Impl& m = *impl_;
  m.ForSegments(batch.n, [&](std::size_t q, int rows) {
    m.EncodeRows(batch, q, rows, m.segment, m.segment.feat.data());
    m.DecodeRows(m.segment.feat.data(), batch, q, rows, m.segment, out, {dropout, dropout_seed, 0});
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
  m.ForSegments(batch.n,
                [&](std::size_t q, int rows) { m.EncodeRows(batch, q, rows, m.segment, encoding + q * d); });
}

template <typename S>
void FieldT<S>::Decode(const S* encoding, const SampleBatchT<S>& batch, FieldOutputT<S>& out, bool dropout,
                       std::uint64_t dropout_seed) {
  CheckBatch(batch, "Field::Decode");
  Impl& m = *impl_;
  const std::size_t d = static_cast<std::size_t>(m.feature_dim());
  m.ForSegments(batch.n, [&](std::size_t q, int rows) {
    m.DecodeRows(encoding + q * d, batch, q, rows, m.segment, out, {dropout, dropout_seed, 0});
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
  auto& a = m.acts;
  const DropoutPass& pass = m.last_pass;
  GrowTo(m.dgeo, rows * std::size_t(config_.heads.geo_features));
  GrowTo(m.dfeat, rows * m.feature_dim());
  m.color.Backward(m.value[kColor].data(), {n, a.dens_raw.data() + 2, m.density.raw_dim(), batch.dir},
                   {a.col_in.data(), a.col_hidden_ptr.data(), a.col_raw.data(), nullptr, nullptr},
                   {g.rgb, g.rgb_logvar}, m.grad[kColor].data(), {m.dgeo.data()}, pass);
  m.density.Backward(m.value[kDensity].data(), {n, a.feat.data()},
                     {a.dens_hidden_ptr.data(), a.dens_raw.data(), nullptr, nullptr},
                     {g.sigma, g.sigma_logvar, m.dgeo.data()}, m.grad[kDensity].data(), {m.dfeat.data()},
                     pass);
  const S* x0 = batch.pos;
  if (m.deform) {
    GrowTo(m.dx0, rows * 3);
    x0 = a.x0.data();
  }
  S* dx0 = m.deform ? m.dx0.data() : nullptr;
  if (m.frequency) {
    m.frequency->Backward(nullptr, {n, x0}, {a.feat.data()}, {m.dfeat.data()}, nullptr, {dx0}, {});
  } else {
    GrowTo(m.dfeats, rows * m.grids->output_dim());
    m.blend->Backward(m.value[kBlend].data(), {n, batch.time, a.gfeat.data()},
                      {a.blend_hidden.data(), a.beta.data(), a.feat.data()}, {m.dfeat.data()},
                      m.grad[kBlend].data(), {m.dfeats.data()}, {});
    m.grids->Backward(m.value[kGrid].data(), {n, x0}, {a.gfeat.data()}, {m.dfeats.data()},
                      m.grad[kGrid].data(), {dx0}, {});
  }
  if (m.deform) {
    m.deform->Backward(m.value[kDeform].data(), {n, batch.pos, batch.time}, {a.x0.data()}, {dx0},
                       m.grad[kDeform].data(), {}, {});
  }
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
std::size_t FieldT<S>::head_macs_per_sample() const {
  return impl_->density.mlp().macs_per_sample() + impl_->color.mlp().macs_per_sample();
}

template class FieldT<float>;
template class FieldT<double>;

}  // namespace endorecon::field
