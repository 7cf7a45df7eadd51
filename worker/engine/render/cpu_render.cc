// The CPU render backend (render_backend.h): the chunk's per-ray bodies of frame_math.h in tbb loops
// and the host field's batched passes, on scratch arrays sized once for the largest chunk.
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <vector>

#include "worker/engine/base/counter_rng.h"
#include "worker/engine/render/frame_math.h"
#include "worker/engine/render/render_backend.h"

namespace endorecon::render {
namespace {

class CpuRender final : public RenderBackend {
 public:
  CpuRender(field::Field& field, const scene::SceneBox& box, const FrameRenderSettings& settings)
      : field_(field), box_(box), settings_(settings) {
    const std::size_t n =
        std::size_t(settings_.rays_per_chunk) * std::max(settings_.coarse_samples, settings_.fine_samples);
    for (auto* v : {&s_, &delta_, &time_, &sigma_, &sigma_lv_, &color_lv_, &weights_, &coarse_s_})
      v->resize(n);
    for (auto* v : {&pos_, &dir_, &color_}) v->resize(3 * n);
    rays_.resize(settings_.rays_per_chunk);
    arrays_ = {rays_.data(),  s_.data(),        delta_.data(),   pos_.data(),
               dir_.data(),   time_.data(),     sigma_.data(),   sigma_lv_.data(),
               color_.data(), color_lv_.data(), weights_.data(), coarse_s_.data()};
    if (settings_.mc_passes > 0) {
      encoding_.resize(n * std::size_t(field_.encoding_dim()));
      density_moments_.resize(n);
      color_moments_.resize(3 * n);
      dropout_.density = density_moments_.data();
      dropout_.color = color_moments_.data();
      for (int i = 0; i < 3; ++i) {
        var_density_[i].resize(n);
        var_color_[i].resize(n);
        dropout_.var_density[i] = var_density_[i].data();
        dropout_.var_color[i] = var_color_[i].data();
      }
    }
    background_params_ = field::BlockValues(field_.Blocks(), "background");
  }

  std::string device() const override { return "cpu"; }

  void Begin(const OccupancyGrid* occupancy) override {
    occupancy_ = occupancy != nullptr && !occupancy->empty()
                     ? OccupancyView{occupancy->cells(), occupancy->resolution()}
                     : OccupancyView{};
  }

  void RenderChunk(const scene::Camera& camera, float time, const int* pixels, int count,
                   std::uint64_t chunk_seed, const PixelOutputs& out) override {
    const ChunkShape shape =
        ChunkShapeOf(settings_, box_, camera, time, occupancy_, settings_.background, background_params_);
    const ChunkArrays& a = arrays_;
    const auto rays = [&](const auto& body) { tbb::parallel_for(0, count, [&](int r) { body(r); }); };
    const auto batch = [&](int samples) { return field::SampleBatch{count * samples, a.pos, a.time, a.dir}; };

    rays([&](int r) { PlaceCoarseRay(shape, a, pixels[r], r); });
    // The coarse weights need the density alone.
    field::FieldOutput coarse{a.sigma, a.sigma_lv, nullptr, a.color_lv};
    field_.Infer(batch(shape.coarse), coarse, /*dropout=*/false, 0);
    rays([&](int r) { CoarseWeights(shape, a, r); });
    rays([&](int r) { PlaceFineRay(shape, a, r); });
    field::FieldOutput fine{a.sigma, a.sigma_lv, a.color, a.color_lv};
    const bool uncertain = settings_.mc_passes > 0;
    if (uncertain) {
      EstimateUncertainty(batch(shape.fine), fine, chunk_seed);
    } else {
      field_.Infer(batch(shape.fine), fine, /*dropout=*/false, 0);
    }
    const DropoutArrays none{};
    const DropoutArrays& d = uncertain ? dropout_ : none;
    rays([&](int r) { FinishRay(shape, a, d, settings_.color_weight, out, r); });
  }

 private:
  // K dropout passes over the fine samples: the deformation, grids and blend are evaluated once (dropout
  // is only in the heads), the heads K times.
  void EstimateUncertainty(const field::SampleBatch& in, field::FieldOutput& out, std::uint64_t chunk_seed) {
    const int passes = settings_.mc_passes;
    const float eps = settings_.variance_eps;
    const std::size_t n = std::size_t(in.n);
    std::fill(density_moments_.begin(), density_moments_.begin() + n, McMoments<float>{});
    std::fill(color_moments_.begin(), color_moments_.begin() + 3 * n, McMoments<float>{});
    field_.Encode(in, encoding_.data());
    const auto samples = [&](const auto& body) {
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 4096),
                        [&](const tbb::blocked_range<std::size_t>& r) {
                          for (std::size_t i = r.begin(); i != r.end(); ++i) body(i);
                        });
    };
    for (int k = 1; k <= passes; ++k) {
      field_.Decode(encoding_.data(), in, out, /*dropout=*/true,
                    base::HashCombine(chunk_seed, std::uint64_t(k)));
      samples([&](std::size_t i) { AddDropoutPass(arrays_, dropout_, k, eps, i); });
    }
    samples([&](std::size_t i) { FinishDropoutPasses(arrays_, dropout_, passes, i); });
  }

  field::Field& field_;
  const scene::SceneBox box_;
  const FrameRenderSettings settings_;
  OccupancyView occupancy_;
  const float* background_params_ = nullptr;  // the host field's learned background, if it has one
  // Scratch for one chunk, reused across chunks and frames.
  std::vector<float> s_, delta_, pos_, dir_, time_, sigma_, sigma_lv_, color_, color_lv_, weights_, coarse_s_;
  std::vector<CameraRay> rays_;
  ChunkArrays arrays_;
  std::vector<float> encoding_;  // the fine samples' field encoding, shared by the K passes
  std::vector<McMoments<float>> density_moments_, color_moments_;
  std::vector<float> var_density_[3], var_color_[3];  // total, aleatoric, epistemic
  DropoutArrays dropout_;
};

}  // namespace

std::unique_ptr<RenderBackend> MakeCpuRender(field::Field& field, const scene::SceneBox& box,
                                             const FrameRenderSettings& settings) {
  return std::make_unique<CpuRender>(field, box, settings);
}

}  // namespace endorecon::render
