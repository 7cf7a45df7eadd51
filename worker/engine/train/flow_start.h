// Where the deformation starts (field/deformation.h): the motion the training frames' optical flow
// shows. Started at zero, the deformation learns large non-rigid motion only from the photometric
// loss, slowly, while the canonical texture is the blur of the misaligned frames; a clip's depth
// tells where every pixel's surface point is, and dense flow from each training frame back to the
// frame at t = 0 (the canonical space) tells where that point was then. The least-squares grid
// through those displacements is the deformation's start; training refines it. A clip without depth
// (a mono recording) lifts its pixels to the clip's typical depth (scene::TypicalDepth): a surface
// at another depth then starts with its sideways motion scaled by the ratio of the two depths, which
// is still closer than no motion (on the real laparoscopic video +0.17 dB held out; docs/benchmarks.md,
// "A mono recording's deformation started from its flow").
#pragma once

#include <cstddef>
#include <nlohmann/json_fwd.hpp>
#include <string>
#include <vector>

#include "worker/engine/field/deformation_math.h"
#include "worker/engine/scene/clip.h"
#include "worker/engine/scene/scene_box.h"

namespace endorecon::train {

struct FlowStart {
  int frames = 0;              // frames whose flow was fitted
  std::size_t points = 0;      // surface points fitted (tool, speculars and inconsistent flow left out)
  double flow_px = 0;          // their mean flow to the reference frame, pixels
  double fitted_fraction = 0;  // 1 - |residual|^2 / |displacement|^2 over the points (weighted)
  double seconds = 0;
  double assumed_depth = 0;  // the depth the pixels were lifted to for a clip without depth; 0: its priors
  std::string skipped;  // why nothing was fitted (params untouched), empty when it was
};

// Writes the deformation's parameters (layout's slices 1..knots) fitted to the flow of `frames`
// (the training frames) to the one of them at time 0. Leaves params as they are, and says why in
// `skipped`, for a clip without a training frame at time 0 or with no usable point.
FlowStart FitDeformationToFlow(const scene::Clip& clip, const std::vector<int>& frames,
                               const scene::SceneBox& box, const field::DeformationLayout& layout,
                               float* params);

// As metrics.json and checkpoints record it: {"from": "optical flow", frames, points, mean_flow_px,
// fitted_fraction, seconds, depth: "priors" or "assumed" (then assumed_depth too)} or {"from": "zero",
// "why"}.
nlohmann::json FlowStartJson(const FlowStart& start);

}  // namespace endorecon::train
