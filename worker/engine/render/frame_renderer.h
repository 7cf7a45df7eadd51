// Renders whole frames from a trained field for any camera at any time: a coarse stratified pass,
// then importance samples placed by the coarse weights (with a uniform floor). Never reads depth
// priors, so held-out frames and novel views are rendered as any other view.
#pragma once

#include <cstdint>
#include <vector>

#include "worker/engine/field/field.h"
#include "worker/engine/scene/camera.h"
#include "worker/engine/scene/scene_box.h"

namespace endorecon::render {

struct FrameRenderSettings {
  double near = 0, far = 1;  // z-depth range sampled, clip units
  int coarse_samples = 48;
  int fine_samples = 48;
  float floor = 0.02f;     // share of fine samples spread uniformly
  int rays_per_chunk = 1024;
};

struct RenderedFrame {
  int width = 0, height = 0;
  std::vector<float> rgb;      // H*W*3 in [0, 1]
  std::vector<float> depth;    // H*W z-depth, clip units: sum_j w_j s_j + (1 - opacity) * far
  std::vector<float> opacity;  // H*W
};

class FrameRenderer {
 public:
  FrameRenderer(field::Field& field, const scene::SceneBox& box, const FrameRenderSettings& settings);

  RenderedFrame Render(const scene::Camera& camera, float time);

  // Renders an explicit list of pixels (row-major indices) of a camera; out arrays sized by the caller.
  void RenderPixels(const scene::Camera& camera, float time, const int* pixels, int count, float* rgb, float* depth,
                    float* opacity);

 private:
  void RenderChunk(const scene::Camera& camera, float time, const int* pixels, int count, float* rgb, float* depth,
                   float* opacity);

  field::Field& field_;
  scene::SceneBox box_;
  FrameRenderSettings settings_;
  // Scratch for one chunk, reused across chunks and frames.
  std::vector<float> s_, delta_, pos_, dir_, time_, sigma_, sigma_lv_, color_, color_lv_, weights_, fine_s_;
};

}  // namespace endorecon::render
