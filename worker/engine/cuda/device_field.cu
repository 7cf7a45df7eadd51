#include <algorithm>
#include <map>
#include <optional>
#include <string>

#include "common/error.h"
#include "worker/engine/cuda/device.h"
#include "worker/engine/cuda/device_field.h"
#include "worker/engine/cuda/device_mlp.h"
#include "worker/engine/cuda/kernels.h"
#include "worker/engine/cuda/launch.cuh"
#include "worker/engine/cuda/step_phases.h"
#include "worker/engine/field/background_math.h"
#include "worker/engine/field/blend_math.h"
#include "worker/engine/field/deformation_math.h"
#include "worker/engine/field/exposure_math.h"
#include "worker/engine/field/frequency_encoding.h"
#include "worker/engine/field/heads_math.h"

namespace endorecon::cuda {
namespace {

// A growable device buffer of floats.
struct Buffer {
  DeviceArray<float> array;
  float* Reserve(std::size_t n) {
    if (array.size() < n) array = DeviceArray<float>(n);
    return array.data();
  }
};

}  // namespace

struct DeviceField::Impl {
  struct Block {
    std::string name;
    DeviceArray<float> value, grad;
  };
  std::vector<Block> blocks;
  std::map<std::string, int> index;  // block name -> blocks[]

  const field::GridEnsemble<float>* grids;
  const field::TemporalBlend<float>* blend;
  const field::FrequencyEncoder<float>* frequency;
  const field::Deformation<float>* deform;
  const field::DensityHead<float>& density;
  const field::ColorHead<float>& color;
  const field::Exposure<float>* exposure;
  DeviceArray<float> exposure_times;   // the knots' times, when the field has an exposure
  DeviceArray<float> exposure_prior;   // ExposurePrior of the current log-gains
  DeviceArray<float> exposure_dprior;  // dL/d(prior) of a backward pass
  std::optional<DeviceMlp> blend_mlp;
  DeviceMlp density_mlp, color_mlp;
  int geo, d;                    // geometry features; encoder width D
  StepPhases* phases = nullptr;  // SetPhases
  void Mark(const char* phase) {
    if (phases) phases->Mark(phase);
  }

  // Activations of the last pass (Forward keeps them for Backward).
  Buffer x0, gfeat, blend_hidden, beta, feat, dens_raw, col_in, col_raw, rgb0, scratch;
  std::vector<Buffer> dens_hidden, col_hidden;
  std::vector<float*> dens_hidden_ptr, col_hidden_ptr, blend_hidden_ptr;
  // Gradients of the backward pass.
  Buffer d_col_raw, d_col_in, dgeo, d_dens_raw, dfeat, dbeta, dlogits, dx0, drgb0;
  int last_n = -1;
  field::DropoutPass last_pass;

  explicit Impl(field::Field& host)
      : grids(host.grids()),
        blend(host.blend()),
        frequency(host.frequency()),
        deform(host.deformation()),
        density(host.density()),
        color(host.color()),
        exposure(host.exposure()),
        density_mlp(host.density().mlp()),
        color_mlp(host.color().mlp()),
        geo(host.config().heads.geo_features),
        d(host.encoding_dim()),
        dens_hidden(host.density().mlp().hidden_layers()),
        col_hidden(host.color().mlp().hidden_layers()) {
    if (blend) blend_mlp.emplace(blend->mlp());
    if (exposure) {
      exposure_times = DeviceArray<float>(exposure->times());
      exposure_prior = DeviceArray<float>(field::kExposurePriorSize);
      exposure_dprior = DeviceArray<float>(field::kExposurePriorSize);
    }
    for (const auto& b : host.Blocks()) {
      index[b.name] = static_cast<int>(blocks.size());
      blocks.push_back({b.name, DeviceArray<float>(b.size), DeviceArray<float>(b.size)});
      blocks.back().grad.Zero();
    }
  }

  float* value(const char* name) { return blocks[index.at(name)].value.data(); }
  float* grad(const char* name) { return blocks[index.at(name)].grad.data(); }

  void Reserve(int n) {
    const std::size_t rows = static_cast<std::size_t>(n);
    x0.Reserve(rows * 3);
    if (grids) {
      gfeat.Reserve(rows * grids->output_dim());
      beta.Reserve(rows * grids->grids());
      blend_hidden_ptr = {blend_hidden.Reserve(rows * blend->hidden_dim())};
    }
    feat.Reserve(rows * d);
    dens_raw.Reserve(rows * density.raw_dim());
    col_in.Reserve(rows * color.in_dim());
    col_raw.Reserve(rows * 4);
    if (exposure) rgb0.Reserve(rows * 3);
    dens_hidden_ptr.clear();
    for (int k = 0; k < density_mlp.hidden_layers(); ++k)
      dens_hidden_ptr.push_back(dens_hidden[k].Reserve(rows * density_mlp.hidden_dim(k)));
    col_hidden_ptr.clear();
    for (int k = 0; k < color_mlp.hidden_layers(); ++k)
      col_hidden_ptr.push_back(col_hidden[k].Reserve(rows * color_mlp.hidden_dim(k)));
  }

  // Deformation, blend weights and grids (or the frequency encoding) into `out_feat` (n x D).
  void Encode(const field::SampleBatch& batch, float* out_feat) {
    const int n = batch.n;
    const float* x = batch.pos;
    if (deform) {
      const field::DeformationLayout layout = deform->layout();
      const float* params = value("deform");
      const float *pos = batch.pos, *time = batch.time;
      float* out = x0.array.data();
      ForEach(
          n,
          [=] __device__(std::size_t i) {
            field::DeformSample(layout, params, pos + 3 * i, time[i], out + 3 * i);
          },
          "deformation kernel");
      x = out;
      Mark("deformation");
    }
    if (frequency) {
      const int frequencies = frequency->frequencies(), width = d;
      ForEach(
          n,
          [=] __device__(std::size_t i) {
            field::FrequencyEncode(x + 3 * i, frequencies, out_feat + i * width);
          },
          "frequency encoding kernel");
      return;
    }
    const int g = grids->grids(), width = d, stride = grids->output_dim();
    float* b = beta.array.data();
    blend_mlp->Forward(value("blend"), batch.time, n, blend_hidden_ptr.data(), b, field::DropoutPass{});
    ForEach(
        n, [=] __device__(std::size_t i) { field::SoftmaxInPlace(b + i * g, g); }, "softmax kernel");
    Mark("blend mlp");
    const float* tables = value("grid");
    float* feats = gfeat.array.data();
    for (int k = 0; k < g; ++k) {
      const auto& grid = grids->grid(k);
      HashGridForward(grid, tables + grids->grid_offset(k), x, n, feats + k * width, stride);
      const int used = grid.output_dim();
      if (used < width) {
        float* base = feats + k * width;
        const int pad = width - used;
        ForEach(
            static_cast<std::size_t>(n) * pad,
            [=] __device__(std::size_t i) { base[(i / pad) * stride + used + i % pad] = 0.0f; },
            "padding kernel");
      }
    }
    Mark("grids");
    ForEach(
        n,
        [=] __device__(std::size_t i) {
          field::BlendFeatures(b + i * g, feats + i * stride, g, width, out_feat + i * width);
        },
        "blend kernel");
    Mark("blend");
  }

  // The heads from `in_feat` (n x D) into out.
  void Decode(const float* in_feat, const field::SampleBatch& batch, field::FieldOutput& out,
              const field::DropoutPass& pass) {
    const int n = batch.n, raw = density.raw_dim(), geo_count = geo, in_dim = color.in_dim();
    const int time_frequencies = color.time_frequencies();
    float* draw = dens_raw.array.data();
    density_mlp.Forward(value("density"), in_feat, n, dens_hidden_ptr.data(), draw, pass);
    Mark("density mlp");
    float *sigma = out.sigma, *sigma_lv = out.sigma_logvar, *rgb = out.rgb, *rgb_lv = out.rgb_logvar;
    if (!rgb) {  // the density alone (field.h)
      ForEach(
          n,
          [=] __device__(std::size_t i) { field::DensityOutputs(draw + i * raw, sigma + i, sigma_lv + i); },
          "density outputs kernel");
      return;
    }
    float* cin = col_in.array.data();
    const float *dir = batch.dir, *time = batch.time;
    ForEach(
        n,
        [=] __device__(std::size_t i) {
          field::DensityOutputs(draw + i * raw, sigma + i, sigma_lv + i);
          field::ColorInput(draw + i * raw + 2, geo_count, dir + 3 * i, time_frequencies ? time[i] : 0.0f,
                            time_frequencies, cin + i * in_dim);
        },
        "density outputs kernel");
    float* craw = col_raw.array.data();
    color_mlp.Forward(value("color"), cin, n, col_hidden_ptr.data(), craw, pass);
    Mark("colour mlp");
    if (!exposure) {
      ForEach(
          n, [=] __device__(std::size_t i) { field::ColorOutputs(craw + 4 * i, rgb + 3 * i, rgb_lv + i); },
          "colour outputs kernel");
      return;
    }
    // The tissue's colour, kept for the backward pass, then the camera's gains at the sample's time.
    float* tissue = rgb0.array.data();
    const float* params = value("exposure");
    const float* times = exposure_times.data();
    const int knots = exposure->knots();
    float* prior = exposure_prior.data();
    ForEach(
        1, [=] __device__(std::size_t) { field::ExposurePrior(params, knots, prior); },
        "exposure prior kernel");
    ForEach(
        n,
        [=] __device__(std::size_t i) {
          field::ColorOutputs(craw + 4 * i, tissue + 3 * i, rgb_lv + i);
          field::ExposureSample(params, prior, times, knots, time[i], tissue + 3 * i, rgb + 3 * i);
        },
        "colour outputs kernel");
  }

  void Backward(const field::SampleBatch& batch, const field::FieldOutputGrad& g) {
    const int n = batch.n, raw = density.raw_dim(), geo_count = geo, in_dim = color.in_dim(), width = d;
    const std::size_t rows = static_cast<std::size_t>(n);
    float* s = scratch.Reserve(
        std::max(density_mlp.scratch_size(n),
                 std::max(color_mlp.scratch_size(n), blend_mlp ? blend_mlp->scratch_size(n) : 0)));
    // Colour head.
    float* dcr = d_col_raw.Reserve(rows * 4);
    const float* craw = col_raw.array.data();
    const float *drgb = g.rgb, *drgb_lv = g.rgb_logvar;
    if (exposure && drgb) {
      // Through the camera's gains to the tissue's colour; the gains' gradient by atomic adds.
      float* dtissue = drgb0.Reserve(rows * 3);
      const float *params = value("exposure"), *times = exposure_times.data(), *time = batch.time;
      const float* tissue = rgb0.array.data();
      float* grads = grad("exposure");
      const int knots = exposure->knots();
      const float* prior = exposure_prior.data();  // the forward pass's, of the same parameters
      float* dprior = exposure_dprior.data();
      exposure_dprior.Zero();
      ForEach(
          n,
          [=] __device__(std::size_t i) {
            field::ExposureSampleBackward(params, prior, times, knots, time[i], tissue + 3 * i, drgb + 3 * i,
                                          dtissue + 3 * i, grads, dprior, AtomicAdd{});
          },
          "exposure backward kernel");
      ForEach(
          1,
          [=] __device__(std::size_t) { field::ExposurePriorBackward(params, knots, prior, dprior, grads); },
          "exposure prior backward kernel");
      drgb = dtissue;
    }
    ForEach(
        n,
        [=] __device__(std::size_t i) {
          field::ColorOutputsBackward(craw + 4 * i, drgb ? drgb + 3 * i : nullptr,
                                      drgb_lv ? drgb_lv + i : nullptr, dcr + 4 * i);
        },
        "colour outputs backward kernel");
    float* dci = d_col_in.Reserve(rows * in_dim);
    color_mlp.Backward(value("color"), col_in.array.data(), n, col_hidden_ptr.data(), dcr, dci, grad("color"),
                       s, last_pass);
    Mark("colour backward");
    // Density head, its geometry features' gradient taken from the colour head's input gradient.
    float* ddr = d_dens_raw.Reserve(rows * raw);
    const float* draw = dens_raw.array.data();
    const float *dsigma = g.sigma, *dsigma_lv = g.sigma_logvar;
    ForEach(
        n,
        [=] __device__(std::size_t i) {
          field::DensityOutputsBackward(draw + i * raw, dsigma ? dsigma + i : nullptr,
                                        dsigma_lv ? dsigma_lv + i : nullptr, dci + i * in_dim, geo_count,
                                        ddr + i * raw);
        },
        "density outputs backward kernel");
    float* df = dfeat.Reserve(rows * width);
    density_mlp.Backward(value("density"), feat.array.data(), n, dens_hidden_ptr.data(), ddr, df,
                         grad("density"), s, last_pass);
    Mark("density backward");
    // Encoder, then the deformation.
    float* dx = deform ? dx0.Reserve(rows * 3) : nullptr;
    const float* x = deform ? x0.array.data() : batch.pos;
    if (dx) ZeroDevice(dx, rows * 3 * sizeof(float));
    if (frequency) {
      const int frequencies = frequency->frequencies();
      if (dx) {
        ForEach(
            n,
            [=] __device__(std::size_t i) {
              field::FrequencyEncodeBackward(x + 3 * i, frequencies, df + i * width, dx + 3 * i);
            },
            "frequency encoding backward kernel");
      }
    } else {
      const int gc = grids->grids(), stride = grids->output_dim();
      const float* b = beta.array.data();
      const float* feats = gfeat.array.data();
      float* db = dbeta.Reserve(rows * gc);
      ForEach(
          n,
          [=] __device__(std::size_t i) {
            field::BlendWeightGradient(df + i * width, feats + i * stride, gc, width, db + i * gc);
          },
          "blend weight gradient kernel");
      const float* tables = value("grid");
      float* table_grads = grad("grid");
      for (int k = 0; k < gc; ++k) {
        const auto& grid = grids->grid(k);
        const std::size_t offset = grids->grid_offset(k);
        HashGridBackward(grid, x, n, df, width, b + k, gc, table_grads + offset,
                         dx ? tables + offset : nullptr, dx);
      }
      Mark("grids backward");
      float* dl = dlogits.Reserve(rows * gc);
      ForEach(
          n,
          [=] __device__(std::size_t i) { field::SoftmaxBackward(b + i * gc, db + i * gc, gc, dl + i * gc); },
          "softmax backward kernel");
      blend_mlp->Backward(value("blend"), batch.time, n, blend_hidden_ptr.data(), dl, nullptr, grad("blend"),
                          s, field::DropoutPass{});
      Mark("blend backward");
    }
    if (deform) {
      const field::DeformationLayout layout = deform->layout();
      const float *pos = batch.pos, *time = batch.time;
      float* grads = grad("deform");
      ForEach(
          n,
          [=] __device__(std::size_t i) {
            field::DeformScatterSample(layout, pos + 3 * i, time[i], dx + 3 * i, grads, 0, AtomicAdd{});
          },
          "deformation backward kernel");
      Mark("deformation backward");
    }
  }
};

DeviceField::DeviceField(field::Field& host) : host_(host), impl_(std::make_unique<Impl>(host)) { Upload(); }

DeviceField::~DeviceField() = default;

void DeviceField::Upload() {
  for (const auto& b : host_.Blocks()) {
    CopyToDevice(impl_->blocks[impl_->index.at(b.name)].value.data(), b.value, b.size * sizeof(float));
  }
}

void DeviceField::Download() {
  for (auto& b : host_.Blocks()) {
    CopyToHost(b.value, impl_->blocks[impl_->index.at(b.name)].value.data(), b.size * sizeof(float));
  }
}

void DeviceField::Forward(const field::SampleBatch& batch, field::FieldOutput& out, bool dropout,
                          std::uint64_t dropout_seed) {
  if (batch.n < 0)
    FailInvalid("DeviceField::Forward: batch size must be >= 0, got " + std::to_string(batch.n));
  if (batch.n > 0 && !out.rgb)
    FailInvalid("DeviceField::Forward: the output needs its rgb array (Backward uses it)");
  Infer(batch, out, dropout, dropout_seed);  // its activations stay in impl_ for Backward
  impl_->last_n = batch.n;
  impl_->last_pass = {dropout, dropout_seed, 0};
}

void DeviceField::Infer(const field::SampleBatch& batch, field::FieldOutput& out, bool dropout,
                        std::uint64_t dropout_seed) {
  if (batch.n < 0) FailInvalid("DeviceField::Infer: batch size must be >= 0, got " + std::to_string(batch.n));
  impl_->Reserve(batch.n);
  impl_->last_n = -1;  // nothing kept to differentiate
  impl_->Encode(batch, impl_->feat.array.data());
  impl_->Decode(impl_->feat.array.data(), batch, out, {dropout, dropout_seed, 0});
}

int DeviceField::encoding_dim() const { return impl_->d; }

void DeviceField::Encode(const field::SampleBatch& batch, float* encoding) {
  impl_->Reserve(batch.n);
  impl_->last_n = -1;
  impl_->Encode(batch, encoding);
}

void DeviceField::Decode(const float* encoding, const field::SampleBatch& batch, field::FieldOutput& out,
                         bool dropout, std::uint64_t dropout_seed) {
  impl_->Reserve(batch.n);
  impl_->last_n = -1;
  impl_->Decode(encoding, batch, out, {dropout, dropout_seed, 0});
}

void DeviceField::Backward(const field::SampleBatch& batch, const field::FieldOutputGrad& grad) {
  if (batch.n != impl_->last_n) {
    Fail(ErrorCode::kFailedPrecondition, "DeviceField::Backward: batch of " + std::to_string(batch.n) +
                                             " samples, but the last Forward had " +
                                             std::to_string(impl_->last_n));
  }
  impl_->Backward(batch, grad);
}

void DeviceField::SetPhases(StepPhases* phases) { impl_->phases = phases; }

void DeviceField::BackgroundBackward(int n, const float* dir, const float* rgb, const float* drgb) {
  if (!host_.background())
    Fail(ErrorCode::kFailedPrecondition, "DeviceField::BackgroundBackward: the field has no background");
  float* grads = impl_->grad("background");
  ForEach(
      n,
      [=] __device__(std::size_t i) {
        field::BackgroundSampleBackward(dir + 3 * i, rgb + 3 * i, drgb + 3 * i, grads, AtomicAdd{});
      },
      "background backward kernel");
}

void DeviceField::ZeroGrad() {
  for (auto& b : impl_->blocks) b.grad.Zero();
}

std::vector<field::ParamBlock<float>> DeviceField::Blocks() {
  std::vector<field::ParamBlock<float>> out;
  for (auto& b : impl_->blocks) out.push_back({b.name, b.value.data(), b.grad.data(), b.value.size()});
  return out;
}

}  // namespace endorecon::cuda
