#include "worker/engine/render/frame_renderer.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <numeric>

#include "worker/engine/render/adaptive_sampler.h"
#include "worker/engine/render/ray_points.h"
#include "worker/engine/render/stratified_sampler.h"
#include "worker/engine/render/volume_renderer.h"

namespace endorecon::render {

FrameRenderer::FrameRenderer(field::Field& field, const scene::SceneBox& box, const FrameRenderSettings& settings)
    : field_(field), box_(box), settings_(settings) {
  const std::size_t n = std::size_t(settings_.rays_per_chunk) *
                        std::max(settings_.coarse_samples, settings_.fine_samples);
  for (auto* v : {&s_, &delta_, &time_, &sigma_, &sigma_lv_, &color_lv_, &weights_, &fine_s_}) v->resize(n);
  for (auto* v : {&pos_, &dir_, &color_}) v->resize(3 * n);
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
  RenderPixels(camera, time, all.data(), pixels, frame.rgb.data(), frame.depth.data(), frame.opacity.data());
  return frame;
}

void FrameRenderer::RenderPixels(const scene::Camera& camera, float time, const int* pixels, int count, float* rgb,
                                 float* depth, float* opacity) {
  for (int start = 0; start < count; start += settings_.rays_per_chunk) {
    const int n = std::min(settings_.rays_per_chunk, count - start);
    RenderChunk(camera, time, pixels + start, n, rgb + 3 * std::size_t(start), depth + start, opacity + start);
  }
}

void FrameRenderer::RenderChunk(const scene::Camera& camera, float time, const int* pixels, int count, float* rgb,
                                float* depth, float* opacity) {
  const float near = float(settings_.near), far = float(settings_.far);
  // Bin centres (uniform 0.5) for the coarse pass and midpoints for the fine one: rendering is
  // deterministic, so the same model gives the same images.
  const auto centre = [](unsigned) { return 0.5f; };
  const auto place = [&](int samples, bool fine) {
    tbb::parallel_for(0, count, [&](int r) {
      Eigen::Vector3d origin, direction;
      camera.Ray(pixels[r] % camera.width, pixels[r] / camera.width, origin, direction);
      const std::size_t o = std::size_t(r) * samples;
      if (fine) {
        const std::size_t c = std::size_t(r) * settings_.coarse_samples;
        AdaptiveSamples(&fine_s_[c], &weights_[c], settings_.coarse_samples, near, far, settings_.floor, samples,
                        centre, &s_[o], &delta_[o]);
      } else {
        StratifiedSamples(near, far, samples, centre, &s_[o], &delta_[o]);
      }
      RayPoints(box_, origin, direction, time, &s_[o], samples, &delta_[o], &pos_[3 * o], &dir_[3 * o], &time_[o]);
    });
    const field::SampleBatch in{count * samples, pos_.data(), time_.data(), dir_.data()};
    field::FieldOutput out{sigma_.data(), sigma_lv_.data(), color_.data(), color_lv_.data()};
    field_.Infer(in, out, /*dropout=*/false, 0);
  };

  place(settings_.coarse_samples, false);
  tbb::parallel_for(0, count, [&](int r) {
    const std::size_t o = std::size_t(r) * settings_.coarse_samples;
    CompositeRay(&sigma_[o], &color_[3 * o], &s_[o], &delta_[o], settings_.coarse_samples, &weights_[o]);
  });
  std::copy(s_.begin(), s_.begin() + std::size_t(count) * settings_.coarse_samples, fine_s_.begin());

  const int m = settings_.fine_samples;
  place(m, true);
  tbb::parallel_for(0, count, [&](int r) {
    const std::size_t o = std::size_t(r) * m;
    const auto ray = CompositeRay(&sigma_[o], &color_[3 * o], &s_[o], &delta_[o], m, &weights_[o]);
    for (int c = 0; c < 3; ++c) rgb[3 * r + c] = ray.rgb[c];
    depth[r] = ray.depth + (1.0f - ray.opacity) * far;
    opacity[r] = ray.opacity;
  });
}

}  // namespace endorecon::render
