#include <algorithm>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "worker/engine/base/counter_rng.h"
#include "worker/engine/cuda/device.h"
#include "worker/engine/cuda/device_field.h"
#include "worker/engine/cuda/device_render.h"
#include "worker/engine/cuda/launch.cuh"
#include "worker/engine/cuda/shared_fields.h"
#include "worker/engine/render/frame_math.h"

namespace endorecon::cuda {
namespace {

class DeviceRender final : public render::RenderBackend {
 public:
  DeviceRender(int index, std::shared_ptr<DeviceField> field, bool shared, const scene::SceneBox& box,
               const render::FrameRenderSettings& settings)
      : index_(index), box_(box), settings_(settings), field_(std::move(field)), shared_(shared) {
    name_ = DeviceName(index);
    const std::size_t rays = static_cast<std::size_t>(settings_.rays_per_chunk);
    const std::size_t n = rays * std::max(settings_.coarse_samples, settings_.fine_samples);
    auto floats = [&](std::size_t count) {
      arrays_.emplace_back(count);
      return arrays_.back().data();
    };
    rays_ = DeviceArray<render::CameraRay>(rays);
    pixels_ = DeviceArray<int>(rays);
    chunk_ = {rays_.data(), floats(n), floats(n),     floats(3 * n), floats(3 * n), floats(n),
              floats(n),    floats(n), floats(3 * n), floats(n),     floats(n),     floats(n)};
    out_.rgb = floats(3 * rays);
    out_.depth = floats(rays);
    out_.opacity = floats(rays);
    if (settings_.mc_passes > 0) {
      encoding_ = DeviceArray<float>(n * static_cast<std::size_t>(field_->encoding_dim()));
      density_moments_ = DeviceArray<render::McMoments<float>>(n);
      color_moments_ = DeviceArray<render::McMoments<float>>(3 * n);
      dropout_.density = density_moments_.data();
      dropout_.color = color_moments_.data();
      for (int i = 0; i < 3; ++i) {
        dropout_.var_density[i] = floats(n);
        dropout_.var_color[i] = floats(n);
      }
      out_.uncertainty = floats(rays);
      out_.aleatoric = floats(rays);
      out_.epistemic = floats(rays);
    }
    background_ = DeviceArray<float>(std::vector<float>(settings_.background, settings_.background + 3));
    background_params_ = field::BlockValues(field_->Blocks(), "background");
  }

  std::string device() const override { return name_; }

  void Begin(const render::OccupancyGrid* occupancy) override {
    SetDevice(index_);
    if (!shared_) field_->Upload();  // a shared copy is the steps' own: already the newest
    occupancy_view_ = {};
    if (occupancy == nullptr || occupancy->empty()) return;
    const int res = occupancy->resolution();
    const std::size_t cells = static_cast<std::size_t>(res) * res * res;
    if (occupancy_.size() != cells) occupancy_ = DeviceArray<std::uint8_t>(cells);
    CopyToDevice(occupancy_.data(), occupancy->cells(), cells);
    occupancy_view_ = {occupancy_.data(), res};
  }

  void RenderChunk(const scene::Camera& camera, float time, const int* pixels, int count,
                   std::uint64_t chunk_seed, const render::PixelOutputs& out) override {
    SetDevice(index_);
    CopyToDevice(pixels_.data(), pixels, static_cast<std::size_t>(count) * sizeof(int));
    const render::ChunkShape shape = render::ChunkShapeOf(settings_, box_, camera, time, occupancy_view_,
                                                          background_.data(), background_params_);
    const render::ChunkArrays a = chunk_;
    const int* device_pixels = pixels_.data();
    const auto batch = [&](int samples) { return field::SampleBatch{count * samples, a.pos, a.time, a.dir}; };

    ForEach(
        count,
        [=] __device__(std::size_t r) {
          render::PlaceCoarseRay(shape, a, device_pixels[r], static_cast<int>(r));
        },
        "coarse placement kernel");
    field::FieldOutput coarse{a.sigma, a.sigma_lv, nullptr, a.color_lv};
    field_->Infer(batch(shape.coarse), coarse, /*dropout=*/false, 0);
    ForEach(
        count, [=] __device__(std::size_t r) { render::CoarseWeights(shape, a, static_cast<int>(r)); },
        "coarse weights kernel");
    ForEach(
        count, [=] __device__(std::size_t r) { render::PlaceFineRay(shape, a, static_cast<int>(r)); },
        "fine placement kernel");
    const field::SampleBatch fine_batch = batch(shape.fine);
    field::FieldOutput fine{a.sigma, a.sigma_lv, a.color, a.color_lv};
    const int passes = settings_.mc_passes;
    const render::DropoutArrays d = passes > 0 ? dropout_ : render::DropoutArrays{};
    if (passes > 0) {
      // The deformation, grids and blend once (dropout is only in the heads), the heads K times.
      const std::size_t n = static_cast<std::size_t>(fine_batch.n);
      ZeroDevice(d.density, n * sizeof(render::McMoments<float>));
      ZeroDevice(d.color, 3 * n * sizeof(render::McMoments<float>));
      field_->Encode(fine_batch, encoding_.data());
      const float eps = settings_.variance_eps;
      for (int k = 1; k <= passes; ++k) {
        field_->Decode(encoding_.data(), fine_batch, fine, /*dropout=*/true,
                       base::HashCombine(chunk_seed, static_cast<std::uint64_t>(k)));
        ForEach(
            n, [=] __device__(std::size_t i) { render::AddDropoutPass(a, d, k, eps, i); },
            "dropout pass kernel");
      }
      ForEach(
          n, [=] __device__(std::size_t i) { render::FinishDropoutPasses(a, d, passes, i); },
          "dropout moments kernel");
    } else {
      field_->Infer(fine_batch, fine, /*dropout=*/false, 0);
    }
    const render::PixelOutputs result = out_;
    const float lambda = settings_.color_weight;
    ForEach(
        count,
        [=] __device__(std::size_t r) {
          render::FinishRay(shape, a, d, lambda, result, static_cast<int>(r));
        },
        "ray finish kernel");
    const std::size_t rays = static_cast<std::size_t>(count);
    CopyToHost(out.rgb, result.rgb, 3 * rays * sizeof(float));
    CopyToHost(out.depth, result.depth, rays * sizeof(float));
    CopyToHost(out.opacity, result.opacity, rays * sizeof(float));
    if (passes == 0) return;
    const std::pair<float*, const float*> scores[3] = {{out.uncertainty, result.uncertainty},
                                                       {out.aleatoric, result.aleatoric},
                                                       {out.epistemic, result.epistemic}};
    for (const auto& [host, device] : scores) {
      if (host != nullptr) CopyToHost(host, device, rays * sizeof(float));
    }
  }

 private:
  int index_;
  std::string name_;
  const scene::SceneBox box_;
  const render::FrameRenderSettings settings_;
  std::shared_ptr<DeviceField> field_;
  bool shared_;  // field_ is the run's copy (shared_fields.h), which the steps keep current
  std::vector<DeviceArray<float>> arrays_;
  DeviceArray<render::CameraRay> rays_;
  DeviceArray<int> pixels_;
  DeviceArray<float> encoding_, background_;
  DeviceArray<render::McMoments<float>> density_moments_, color_moments_;
  DeviceArray<std::uint8_t> occupancy_;
  render::OccupancyView occupancy_view_;
  render::ChunkArrays chunk_;
  render::DropoutArrays dropout_;
  render::PixelOutputs out_;                  // the chunk's results on the device
  const float* background_params_ = nullptr;  // the device field's learned background, if it has one
};

}  // namespace

render::RenderBackendFactory DeviceRenderFactory(int index, std::shared_ptr<SharedFields> shared) {
  return [index, shared](field::Field& field, const scene::SceneBox& box,
                         const render::FrameRenderSettings& settings) {
    SetDevice(index);
    return std::unique_ptr<render::RenderBackend>(
        new DeviceRender(index, DeviceFieldFor(shared.get(), field), shared != nullptr, box, settings));
  };
}

}  // namespace endorecon::cuda
