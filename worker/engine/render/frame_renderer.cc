#include "worker/engine/render/frame_renderer.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <numeric>

#include "worker/engine/base/counter_rng.h"
#include "worker/engine/field/variance.h"
#include "worker/engine/render/adaptive_sampler.h"
#include "worker/engine/render/camera_ray.h"
#include "worker/engine/render/sample_score.h"
#include "worker/engine/render/stratified_sampler.h"
#include "worker/engine/render/volume_renderer.h"

namespace endorecon::render {

FrameRenderer::FrameRenderer(field::Field& field, const scene::SceneBox& box,
                             const FrameRenderSettings& settings)
    : field_(field), box_(box), settings_(settings) {
  const std::size_t n =
      std::size_t(settings_.rays_per_chunk) * std::max(settings_.coarse_samples, settings_.fine_samples);
  for (auto* v : {&s_, &delta_, &time_, &sigma_, &sigma_lv_, &color_lv_, &weights_, &fine_s_}) v->resize(n);
  for (auto* v : {&pos_, &dir_, &color_}) v->resize(3 * n);
  rays_.resize(settings_.rays_per_chunk);
  if (field_.background()) {
    ray_dir_.resize(3 * std::size_t(settings_.rays_per_chunk));
    background_.resize(3 * std::size_t(settings_.rays_per_chunk));
  }
  if (settings_.mc_passes > 0) {
    encoding_.resize(n * std::size_t(field_.encoding_dim()));
    density_moments_.resize(n);
    color_moments_.resize(3 * n);
    for (int i = 0; i < 3; ++i) {
      var_density_[i].resize(n);
      var_color_[i].resize(n);
    }
  }
}

RenderedFrame FrameRenderer::Render(const scene::Camera& camera, float time) {
  RenderedFrame frame;
  frame.width = camera.width;
  frame.height = camera.height;
  const int pixels = camera.width * camera.height;
  frame.rgb.resize(3 * std::size_t(pixels));
  frame.depth.resize(pixels);
  frame.opacity.resize(pixels);
  std::vector<int> all(pixels);
  std::iota(all.begin(), all.end(), 0);
  PixelOutputs out{frame.rgb.data(), frame.depth.data(), frame.opacity.data()};
  if (settings_.mc_passes > 0) {
    for (auto* v : {&frame.uncertainty, &frame.aleatoric, &frame.epistemic}) v->resize(pixels);
    out.uncertainty = frame.uncertainty.data();
    out.aleatoric = frame.aleatoric.data();
    out.epistemic = frame.epistemic.data();
  }
  RenderPixels(camera, time, all.data(), pixels, out);
  return frame;
}

void FrameRenderer::RenderPixels(const scene::Camera& camera, float time, const int* pixels, int count,
                                 const PixelOutputs& out) {
  const auto at = [](float* p, int offset) { return p ? p + offset : nullptr; };
  for (int start = 0; start < count; start += settings_.rays_per_chunk) {
    const int n = std::min(settings_.rays_per_chunk, count - start);
    const PixelOutputs chunk{at(out.rgb, 3 * start),     at(out.depth, start),     at(out.opacity, start),
                             at(out.uncertainty, start), at(out.aleatoric, start), at(out.epistemic, start)};
    RenderChunk(camera, time, pixels + start, n, chunk);
  }
}

void FrameRenderer::EstimateUncertainty(int n, std::uint64_t chunk_seed) {
  const int passes = settings_.mc_passes;
  const float eps = settings_.variance_eps;
  std::fill(density_moments_.begin(), density_moments_.begin() + n, McMoments<float>{});
  std::fill(color_moments_.begin(), color_moments_.begin() + 3 * std::size_t(n), McMoments<float>{});
  const field::SampleBatch in{n, pos_.data(), time_.data(), dir_.data()};
  field::FieldOutput out{sigma_.data(), sigma_lv_.data(), color_.data(), color_lv_.data()};
  // Dropout is only in the heads: the deformation, grids and blend are evaluated once for all passes.
  field_.Encode(in, encoding_.data());
  for (int k = 1; k <= passes; ++k) {
    field_.Decode(encoding_.data(), in, out, /*dropout=*/true,
                  base::HashCombine(chunk_seed, std::uint64_t(k)));
    tbb::parallel_for(tbb::blocked_range<int>(0, n, 4096), [&](const tbb::blocked_range<int>& range) {
      for (int i = range.begin(); i != range.end(); ++i) {
        AddPass(density_moments_[i], k, sigma_[i], field::VarianceFromLogVar(sigma_lv_[i], eps));
        const float color_var = field::VarianceFromLogVar(color_lv_[i], eps);
        for (int c = 0; c < 3; ++c)
          AddPass(color_moments_[3 * std::size_t(i) + c], k, color_[3 * i + c], color_var);
      }
    });
  }
  tbb::parallel_for(tbb::blocked_range<int>(0, n, 4096), [&](const tbb::blocked_range<int>& range) {
    for (int i = range.begin(); i != range.end(); ++i) {
      const McMoments<float>& d = density_moments_[i];
      const McMoments<float>* c = &color_moments_[3 * std::size_t(i)];
      sigma_[i] = d.mean;
      float color_epistemic = 0;
      for (int ch = 0; ch < 3; ++ch) {
        color_[3 * i + ch] = c[ch].mean;
        color_epistemic += Epistemic(c[ch], passes) / 3.0f;
      }
      var_density_[1][i] = Aleatoric(d, passes);
      var_density_[2][i] = Epistemic(d, passes);
      var_color_[1][i] = Aleatoric(c[0], passes);
      var_color_[2][i] = color_epistemic;
      var_density_[0][i] = var_density_[1][i] + var_density_[2][i];
      var_color_[0][i] = var_color_[1][i] + var_color_[2][i];
    }
  });
}

void FrameRenderer::RenderChunk(const scene::Camera& camera, float time, const int* pixels, int count,
                                const PixelOutputs& result) {
  const float near = float(settings_.near), far = float(settings_.far);
  // Bin centres (uniform 0.5) for the coarse pass and midpoints for the fine one: rendering is
  // deterministic, so the same model gives the same images.
  const auto centre = [](unsigned) { return 0.5f; };
  const auto place = [&](int samples, bool fine, bool evaluate) {
    tbb::parallel_for(0, count, [&](int r) {
      const RaySlot slot =
          RaySlotOf(s_.data(), delta_.data(), pos_.data(), dir_.data(), time_.data(), r, samples);
      if (fine) {
        const std::size_t c = std::size_t(r) * settings_.coarse_samples;
        PlaceSamples(
            rays_[r], box_.Frame(), time, samples,
            [&](float lo, float hi, float* s, float* delta) {
              AdaptiveSamples(&fine_s_[c], &weights_[c], settings_.coarse_samples, lo, hi, settings_.floor,
                              samples, centre, s, delta);
            },
            slot);
      } else {
        rays_[r] = CameraRayOf(camera, pixels[r], box_, occupancy_, near, far);
        PlaceSamples(
            rays_[r], box_.Frame(), time, samples,
            [&](float lo, float hi, float* s, float* delta) {
              StratifiedSamples(lo, hi, samples, centre, s, delta);
            },
            slot);
      }
    });
    if (!evaluate) return;
    // The coarse pass only places the fine samples: its weights need the density alone.
    const field::SampleBatch in{count * samples, pos_.data(), time_.data(), dir_.data()};
    field::FieldOutput out{sigma_.data(), sigma_lv_.data(), fine ? color_.data() : nullptr, color_lv_.data()};
    field_.Infer(in, out, /*dropout=*/false, 0);
  };

  place(settings_.coarse_samples, false, true);
  tbb::parallel_for(0, count, [&](int r) {
    // Only the weights are used: the colour composited here (color_ as a previous chunk left it) is not.
    const std::size_t o = std::size_t(r) * settings_.coarse_samples;
    CompositeRay(&sigma_[o], &color_[3 * o], &s_[o], &delta_[o], settings_.coarse_samples, &weights_[o]);
  });
  std::copy(s_.begin(), s_.begin() + std::size_t(count) * settings_.coarse_samples, fine_s_.begin());

  const int m = settings_.fine_samples;
  const bool uncertain = settings_.mc_passes > 0;
  place(m, true, !uncertain);
  if (uncertain)
    EstimateUncertainty(count * m, base::HashCombine(settings_.mc_seed, std::uint64_t(pixels[0])));
  const bool learned_background = field_.background() != nullptr;
  if (learned_background) {
    tbb::parallel_for(
        0, count, [&](int r) { scene::UnitDirection(rays_[r].direction, &ray_dir_[3 * std::size_t(r)]); });
    field_.BackgroundRgb(count, ray_dir_.data(), background_.data());
  }
  float* scores[3] = {result.uncertainty, result.aleatoric, result.epistemic};
  tbb::parallel_for(0, count, [&](int r) {
    const std::size_t o = std::size_t(r) * m;
    auto ray = CompositeRay(&sigma_[o], &color_[3 * o], &s_[o], &delta_[o], m, &weights_[o]);
    AddBackground(ray, learned_background ? &background_[3 * std::size_t(r)] : settings_.background);
    for (int c = 0; c < 3; ++c) result.rgb[3 * r + c] = ray.rgb[c];
    result.depth[r] = ray.depth + (1.0f - ray.opacity) * far;
    result.opacity[r] = ray.opacity;
    if (!uncertain) return;
    for (int i = 0; i < 3; ++i) {
      if (scores[i]) {
        scores[i][r] =
            RayScore(&weights_[o], &var_density_[i][o], &var_color_[i][o], m, settings_.color_weight);
      }
    }
  });
}

}  // namespace endorecon::render
