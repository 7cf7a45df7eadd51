#include "worker/engine/render/frame_renderer.h"

#include <algorithm>
#include <numeric>

#include "worker/engine/base/counter_rng.h"

namespace endorecon::render {

FrameRenderer::FrameRenderer(field::Field& field, const scene::SceneBox& box,
                             const FrameRenderSettings& settings, const RenderBackendFactory& backend)
    : settings_(settings), backend_(backend(field, box, settings_)) {}

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
  if (count <= 0) return;
  backend_->Begin(occupancy_);
  const auto at = [](float* p, int offset) { return p ? p + offset : nullptr; };
  for (int start = 0; start < count; start += settings_.rays_per_chunk) {
    const int n = std::min(settings_.rays_per_chunk, count - start);
    const PixelOutputs chunk{at(out.rgb, 3 * start),     at(out.depth, start),     at(out.opacity, start),
                             at(out.uncertainty, start), at(out.aleatoric, start), at(out.epistemic, start)};
    const std::uint64_t chunk_seed = base::HashCombine(settings_.mc_seed, std::uint64_t(pixels[start]));
    backend_->RenderChunk(camera, time, pixels + start, n, chunk_seed, chunk);
  }
}

}  // namespace endorecon::render
