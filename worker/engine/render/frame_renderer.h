// Renders whole frames from a trained field for any camera at any time: a coarse stratified pass
// (over the ray's occupied span when an occupancy grid is set), then importance samples placed by
// the coarse weights (with a uniform floor). Never reads depth
// priors, so held-out frames and novel views are rendered as any other view.
// With mc_passes = K > 0 it also estimates uncertainty (paper §3): the samples are placed by a
// dropout-off coarse pass as always, then the fine samples are evaluated K times with dropout on;
// colour and depth are rendered from the K-pass mean density and colour, and each pixel gets the
// ray score S_ray = sum_j w_j (var_sigma,j + lambda var_c,j) / sum_j w_j (sample_score.h RayScore,
// raw variances) of the total, the aleatoric and the epistemic variances. The colour variances are
// one per sample: the head predicts one aleatoric variance for the three channels, and the
// epistemic one is the mean over the channels of each channel's variance across passes.
#pragma once

#include <cstdint>
#include <vector>

#include "worker/engine/field/field.h"
#include "worker/engine/field/variance.h"
#include "worker/engine/render/camera_ray.h"
#include "worker/engine/render/mc_dropout.h"
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

struct RenderedFrame {
  int width = 0, height = 0;
  std::vector<float> rgb;      // H*W*3 in [0, 1], the background seen through what is transparent
  std::vector<float> depth;    // H*W z-depth, clip units: sum_j w_j s_j + (1 - opacity) * far
  std::vector<float> opacity;  // H*W
  // H*W ray scores with mc_passes > 0, else empty: total = aleatoric + epistemic (per sample).
  std::vector<float> uncertainty, aleatoric, epistemic;
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

class FrameRenderer {
 public:
  FrameRenderer(field::Field& field, const scene::SceneBox& box, const FrameRenderSettings& settings);

  // Empty-space skipping: with a grid, each ray's coarse samples cover only its occupied span
  // (occupancy_grid.h). The grid must outlive its use; null (the default) samples all of [near, far].
  void SetOccupancy(const OccupancyGrid* grid) { occupancy_ = grid; }

  RenderedFrame Render(const scene::Camera& camera, float time);

  // Renders an explicit list of pixels (row-major indices) of a camera; out arrays sized by the caller.
  void RenderPixels(const scene::Camera& camera, float time, const int* pixels, int count,
                    const PixelOutputs& out);

  const FrameRenderSettings& settings() const { return settings_; }

 private:
  void RenderChunk(const scene::Camera& camera, float time, const int* pixels, int count,
                   const PixelOutputs& out);
  // K dropout passes over the first n placed samples: leaves the means in sigma_ / color_ and the
  // per-sample total, aleatoric and epistemic variances in the var_* arrays.
  void EstimateUncertainty(int n, std::uint64_t chunk_seed);

  field::Field& field_;
  scene::SceneBox box_;
  FrameRenderSettings settings_;
  const OccupancyGrid* occupancy_ = nullptr;
  // Scratch for one chunk, reused across chunks and frames.
  std::vector<float> s_, delta_, pos_, dir_, time_, sigma_, sigma_lv_, color_, color_lv_, weights_, fine_s_;
  std::vector<CameraRay> rays_;              // per ray of the chunk: the ray and the span sampled
  std::vector<float> ray_dir_, background_;  // per ray of the chunk, with a learned background: d, bg(d)
  std::vector<float> encoding_;              // the fine samples' field encoding, shared by the K passes
  std::vector<McMoments<float>> density_moments_, color_moments_;  // n and 3n, with mc_passes > 0
  std::vector<float> var_density_[3], var_color_[3];               // total, aleatoric, epistemic
};

}  // namespace endorecon::render
