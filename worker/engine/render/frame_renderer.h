// Renders whole frames from a trained field for any camera at any time: a coarse stratified pass
// (over the ray's occupied span when an occupancy grid is set), then importance samples placed by
// the coarse weights (with a uniform floor). Never reads depth
// priors, so held-out frames and novel views are rendered as any other view.
// With mc_passes = K > 0 it also estimates uncertainty (paper §3): the samples are placed by a
// dropout-off coarse pass as always, then the fine samples are evaluated K times with dropout on;
// colour and depth are rendered from the K-pass mean density and colour, and each pixel gets the
// ray score S_ray = sum_j w_j (var_sigma,j + lambda var_c,j) / sum_j w_j (sample_score.h RayScore,
// raw variances) of the total, the aleatoric and the epistemic variances (frame_math.h).
// The chunks run on a RenderBackend (render_backend.h): the CPU by default, or a GPU.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "worker/engine/render/render_backend.h"

namespace endorecon::render {

struct RenderedFrame {
  int width = 0, height = 0;
  std::vector<float> rgb;      // H*W*3 in [0, 1], the background seen through what is transparent
  std::vector<float> depth;    // H*W z-depth, clip units: sum_j w_j s_j + (1 - opacity) * far
  std::vector<float> opacity;  // H*W
  // H*W ray scores with mc_passes > 0, else empty: total = aleatoric + epistemic (per sample).
  std::vector<float> uncertainty, aleatoric, epistemic;
};

class FrameRenderer {
 public:
  // The field and box must outlive the renderer; `backend` makes where the chunks run.
  FrameRenderer(field::Field& field, const scene::SceneBox& box, const FrameRenderSettings& settings,
                const RenderBackendFactory& backend = MakeCpuRender);

  // Empty-space skipping: with a grid, each ray's coarse samples cover only its occupied span
  // (occupancy_grid.h). The grid must outlive its use; null (the default) samples all of [near, far].
  void SetOccupancy(const OccupancyGrid* grid) { occupancy_ = grid; }

  // A stop asked for (a cancel, a worker's shutdown) ends a render between its chunks (1,024 rays):
  // Render and RenderPixels throw Error(kCancelled). A large frame with uncertainty took 20-30 s on two
  // loaded cores, so a stop waited that long (found 2026-12-07). Empty (the default): never stops.
  void SetStop(std::function<bool()> stop) { stop_ = std::move(stop); }

  // `skip` (empty, or one value per pixel): pixels left unrendered where it is nonzero (outside a
  // scope's view), given black, depth 0 (unknown), opacity 0 and no uncertainty.
  RenderedFrame Render(const scene::Camera& camera, float time, std::span<const std::uint8_t> skip = {});

  // Renders an explicit list of pixels (row-major indices) of a camera; out arrays sized by the caller.
  void RenderPixels(const scene::Camera& camera, float time, const int* pixels, int count,
                    const PixelOutputs& out);

  const FrameRenderSettings& settings() const { return settings_; }

  // Where the chunks run ("cpu", "cuda:0 (...)").
  std::string device() const { return backend_->device(); }

 private:
  FrameRenderSettings settings_;
  const OccupancyGrid* occupancy_ = nullptr;
  std::function<bool()> stop_;
  std::unique_ptr<RenderBackend> backend_;
};

}  // namespace endorecon::render
