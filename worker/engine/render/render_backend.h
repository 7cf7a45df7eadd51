// Where a chunk of pixels is rendered. There is one FrameRenderer (frame_renderer.h: frames, pixel
// lists, chunking, the dropout seeds of chunks, the occupancy grid); it drives a RenderBackend, which
// decides only where the chunk's samples and the field's parameters live and how the per-ray loops of
// frame_math.h are launched: the CPU backend (MakeCpuRender, the reference) on the host field, a GPU
// backend (cuda/device_render.h, built with CUDA) on a device copy of it.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include "worker/engine/field/field.h"
#include "worker/engine/field/variance.h"
#include "worker/engine/render/occupancy_grid.h"
#include "worker/engine/scene/camera.h"
#include "worker/engine/scene/scene_box.h"

namespace endorecon::render {

struct FrameRenderSettings {
  double near = 0, far = 1;  // z-depth range sampled, clip units
  int coarse_samples = 48;
  int fine_samples = 48;
  float floor = 0.02f;  // share of fine samples spread uniformly
  int rays_per_chunk = 1024;
  int mc_passes = 0;          // K dropout passes for uncertainty; 0 = no uncertainty (one dropout-off pass)
  float color_weight = 1.0f;  // lambda of the ray score
  float variance_eps = field::kDefaultVarianceEps;  // eps in var = softplus(l) + eps
  std::uint64_t mc_seed = 0;  // dropout masks of pass k in a chunk: a pure function of (seed, k, first pixel)
  // What rays see past the samples (RGB in [0, 1]); a field with a learned background (field.h
  // BackgroundRgb) is rendered on that instead.
  float background[3] = {0, 0, 0};
};

// Where RenderPixels writes, one entry per pixel (rgb three); the uncertainty arrays may be null
// (not computed unless mc_passes > 0; left untouched otherwise).
struct PixelOutputs {
  float* rgb = nullptr;
  float* depth = nullptr;
  float* opacity = nullptr;
  float* uncertainty = nullptr;
  float* aleatoric = nullptr;
  float* epistemic = nullptr;
};

class RenderBackend {
 public:
  virtual ~RenderBackend() = default;

  // "cpu", or the GPU's name ("cuda:0 (NVIDIA H200)").
  virtual std::string device() const = 0;
  // Before the chunks of one RenderPixels call: the field's parameters and the occupancy grid (null or
  // empty: none) as they are now; a backend that keeps copies refreshes them (a GPU backend sharing
  // the training step's device copy has no parameters to refresh: the steps write there).
  virtual void Begin(const OccupancyGrid* occupancy) = 0;
  // Renders `count` (at most settings.rays_per_chunk) pixels of the camera at `time` into `out` (host
  // arrays, offset to the chunk's first pixel); the K dropout passes use masks
  // HashCombine(chunk_seed, k), as field::Field's Decode takes them.
  virtual void RenderChunk(const scene::Camera& camera, float time, const int* pixels, int count,
                           std::uint64_t chunk_seed, const PixelOutputs& out) = 0;
};

// Makes a backend for a host field, scene box and settings (which outlive it).
using RenderBackendFactory = std::function<std::unique_ptr<RenderBackend>(
    field::Field& field, const scene::SceneBox& box, const FrameRenderSettings& settings)>;

std::unique_ptr<RenderBackend> MakeCpuRender(field::Field& field, const scene::SceneBox& box,
                                             const FrameRenderSettings& settings);

}  // namespace endorecon::render
