// "Leave out what a scene does not need": adapts a config to the clip at hand and records what was
// left out and why (it goes into metrics.json). No masks: no mask handling; no depth: no depth loss
// and no depth-guided sampling; a static clip: no deformation; hash levels finer than a pixel's
// footprint in the scene: dropped; a steady exposure (exposure "auto"): no per-frame gains.
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "worker/engine/scene/camera.h"
#include "worker/engine/scene/clip.h"
#include "worker/engine/train/train_config.h"

namespace endorecon::train {

struct SceneFit {
  nlohmann::json left_out = nlohmann::json::array();  // [{"what": ..., "why": ...}]
  int preview_width = 64;

  // The camera scaled down to preview size (same view, fewer pixels).
  scene::Camera preview_camera(const scene::Camera& camera) const;
};

// Changes `config` in place (idempotent: a config that was already fitted stays as it is).
// train_frames: the frames training sees (the exposure's knots); empty: every frame.
SceneFit FitToScene(const scene::Clip& clip, TrainConfig& config, std::vector<int> train_frames = {});

}  // namespace endorecon::train
