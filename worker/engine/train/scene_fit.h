// "Leave out what a scene does not need": adapts a config to the clip at hand and records what was
// left out and why (it goes into metrics.json). No masks: no mask handling; no depth: no depth loss
// and no depth-guided sampling; a static clip, or one whose tissue stands still: no deformation; hash levels
// finer than a pixel's footprint in the scene: dropped; a steady exposure (exposure "auto"): no per-frame
// gains; frames too many or too large for the guided rays' uncertainty map at its stride: a coarser map.
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "worker/engine/scene/camera.h"
#include "worker/engine/scene/clip.h"
#include "worker/engine/train/train_config.h"

namespace endorecon::train {

struct SceneFit {
  nlohmann::json left_out = nlohmann::json::array();  // [{"what": ..., "why": ...}]
  // What a measurement kept that it could have left out, and what it measured (the exposure gains
  // of "auto", the deformation of a clip tested for stillness): [{"what": ..., "why": ...}].
  nlohmann::json kept = nlohmann::json::array();
  int preview_width = 64;

  // The camera scaled down to preview size (same view, fewer pixels).
  scene::Camera preview_camera(const scene::Camera& camera) const;
};

// The uncertainty map (uncertainty_map.h) has a cell per stride x stride pixels of every training
// frame, and each refresh scores one ray per cell with a dropout-on pass at the training samples
// (about a third of a trained ray's cost), every adaptive_refresh steps. Its cells are kept to at most
// this share of the rays trained between two refreshes, so a refresh costs about 4% of the training:
// the demo clip's 42 frames of 160 x 128 keep stride 4 (53,760 cells against 65,536), 140 frames of
// 640 x 512 take stride 27 at the cpu preset's 1,024 rays a step, where stride 4 spent two thirds of
// the training in refreshes (docs/benchmarks.md, "The uncertainty map's stride from the clip").
inline constexpr double kMapProbeShare = 0.125;

// The smallest stride, not below config.adaptive_map_stride, whose map of `frames` frames of
// width x height has at most kMapProbeShare x adaptive_refresh x rays_per_batch cells.
int UncertaintyMapStride(int width, int height, int frames, const TrainConfig& config);

// Changes `config` in place (idempotent: a config that was already fitted stays as it is).
// train_frames: the frames training sees (the exposure's knots); empty: every frame.
SceneFit FitToScene(const scene::Clip& clip, TrainConfig& config, std::vector<int> train_frames = {});

}  // namespace endorecon::train
