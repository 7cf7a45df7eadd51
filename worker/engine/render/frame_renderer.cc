#include "worker/engine/render/frame_renderer.h"

#include <algorithm>
#include <string>

#include "common/error.h"
#include "worker/engine/base/counter_rng.h"

namespace endorecon::render {

FrameRenderer::FrameRenderer(field::Field& field, const scene::SceneBox& box,
                             const FrameRenderSettings& settings, const RenderBackendFactory& backend)
    : settings_(settings), backend_(backend(field, box, settings_)) {}

RenderedFrame FrameRenderer::Render(const scene::Camera& camera, float time,
                                    std::span<const std::uint8_t> skip) {
  RenderedFrame frame;
  frame.width = camera.width;
  frame.height = camera.height;
  const int pixels = camera.width * camera.height;
  if (!skip.empty() && int(skip.size()) != pixels) {
    FailInvalid("render: a skip mask of " + std::to_string(skip.size()) + " values for " +
                std::to_string(pixels) + " pixels");
  }
  const bool uncertain = settings_.mc_passes > 0;
  frame.rgb.assign(3 * std::size_t(pixels), 0.0f);
  frame.depth.assign(pixels, 0.0f);
  frame.opacity.assign(pixels, 0.0f);
  if (uncertain) {
    for (auto* v : {&frame.uncertainty, &frame.aleatoric, &frame.epistemic}) v->assign(pixels, 0.0f);
  }
  std::vector<int> rendered;
  rendered.reserve(pixels);
  for (int p = 0; p < pixels; ++p) {
    if (skip.empty() || skip[p] == 0) rendered.push_back(p);
  }
  const auto outputs = [&](RenderedFrame& f) {
    PixelOutputs out{f.rgb.data(), f.depth.data(), f.opacity.data()};
    if (uncertain) {
      out.uncertainty = f.uncertainty.data();
      out.aleatoric = f.aleatoric.data();
      out.epistemic = f.epistemic.data();
    }
    return out;
  };
  const int count = int(rendered.size());
  if (count == pixels) {
    RenderPixels(camera, time, rendered.data(), count, outputs(frame));
    return frame;
  }
  // Rendered compactly, then placed at their pixels.
  RenderedFrame part;
  part.rgb.resize(3 * std::size_t(count));
  for (auto* v : {&part.depth, &part.opacity}) v->resize(count);
  if (uncertain) {
    for (auto* v : {&part.uncertainty, &part.aleatoric, &part.epistemic}) v->resize(count);
  }
  RenderPixels(camera, time, rendered.data(), count, outputs(part));
  for (int i = 0; i < count; ++i) {
    const int p = rendered[i];
    for (int c = 0; c < 3; ++c) frame.rgb[3 * std::size_t(p) + c] = part.rgb[3 * std::size_t(i) + c];
    frame.depth[p] = part.depth[i];
    frame.opacity[p] = part.opacity[i];
    if (uncertain) {
      frame.uncertainty[p] = part.uncertainty[i];
      frame.aleatoric[p] = part.aleatoric[i];
      frame.epistemic[p] = part.epistemic[i];
    }
  }
  return frame;
}

void FrameRenderer::RenderPixels(const scene::Camera& camera, float time, const int* pixels, int count,
                                 const PixelOutputs& out) {
  if (count <= 0) return;
  backend_->Begin(occupancy_);
  const auto at = [](float* p, int offset) { return p ? p + offset : nullptr; };
  for (int start = 0; start < count; start += settings_.rays_per_chunk) {
    if (stop_ && stop_()) Fail(ErrorCode::kCancelled, "stopped while a frame rendered");
    const int n = std::min(settings_.rays_per_chunk, count - start);
    const PixelOutputs chunk{at(out.rgb, 3 * start),     at(out.depth, start),     at(out.opacity, start),
                             at(out.uncertainty, start), at(out.aleatoric, start), at(out.epistemic, start)};
    const std::uint64_t chunk_seed = base::HashCombine(settings_.mc_seed, std::uint64_t(pixels[start]));
    backend_->RenderChunk(camera, time, pixels + start, n, chunk_seed, chunk);
  }
}

}  // namespace endorecon::render
