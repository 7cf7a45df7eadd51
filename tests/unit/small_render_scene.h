// A tiny render setup for tests of a frame's render: a 12 x 10 camera, a 4-level CPU field and
// settings that split the frame into several chunks, over the camera's frustum between 0.5 and 2.
#pragma once

#include "worker/engine/field/field.h"
#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/scene/camera.h"

namespace endorecon::testing {

inline scene::Camera SmallCamera() {
  scene::Camera camera;
  camera.width = 12;
  camera.height = 10;
  camera.fx = camera.fy = 10;
  camera.cx = 6;
  camera.cy = 5;
  return camera;
}

inline field::FieldConfig SmallField(double dropout) {
  field::FieldConfig config = field::FieldConfig::Cpu();
  config.grids.levels = 4;
  config.heads.dropout = dropout;
  return config;
}

// `passes` dropout passes (0: none); near 0.5, far 2.
inline render::FrameRenderSettings SmallRenderSettings(int passes) {
  render::FrameRenderSettings settings;
  settings.near = 0.5;
  settings.far = 2.0;
  settings.coarse_samples = 16;
  settings.fine_samples = 16;
  settings.rays_per_chunk = 50;  // several chunks per frame
  settings.mc_passes = passes;
  settings.mc_seed = 9;
  return settings;
}

}  // namespace endorecon::testing
