// The in-memory clip every loader produces and the rest of the engine consumes.
// Frames are row-major, top row first. Optional parts are empty vectors when the clip lacks them;
// the engine leaves out the machinery for whatever is absent (no masks: no mask handling; no depth:
// no depth loss or depth-guided sampling; static: no deformation).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "worker/engine/scene/camera.h"

namespace endorecon::scene {

struct Clip {
  std::string source;  // where it was loaded from (for messages)
  int width = 0, height = 0;
  double near = 0, far = 1;  // z-depth bounds over the whole clip, clip units

  std::vector<Camera> cameras;                // one per frame
  std::vector<float> times;                   // one per frame, in [0, 1]
  std::vector<std::vector<std::uint8_t>> rgb;  // one per frame, H*W*3, RGB order
  std::vector<std::vector<float>> depth;       // empty or one per frame, H*W, clip units; 0 = unknown
  std::vector<std::vector<std::uint8_t>> tool_mask;  // empty or one per frame, H*W, 1 = tool
  std::vector<std::vector<std::uint8_t>> eval_mask;  // empty or one per frame (gt_masks/), 1 = tool
  // Empty or H*W, 1 = outside the scope's view (scene/outside_view.h): set in every frame's masks
  // too, and kept apart so that it does not count as occlusion.
  std::vector<std::uint8_t> outside_view;

  // Stereo: the other eye, when the clip has images_right/. Cameras are the left cameras
  // shifted by the baseline (a user-supplied or default value; see docs/formats.md).
  std::vector<Camera> right_cameras;
  std::vector<std::vector<std::uint8_t>> right_rgb;

  // Ground truth the EndoNeRF layout has no slot for (synthetic clips): tool-free images and
  // float z-depth per frame. Training never reads these; evaluation does.
  std::vector<std::vector<std::uint8_t>> gt_rgb;
  std::vector<std::vector<float>> gt_depth;

  bool is_static = false;  // no per-frame time, or the user said --static
  // Why LoadClip brought near and far to the depth priors (scene/depth_bounds.h); empty: as given.
  std::string bounds_fitted;

  // Object captures (NeRF-synthetic style): the images had transparent pixels, composited onto
  // LoadOptions::alpha_background when read; and the cameras stand around an object at the origin
  // (a centred rig): it lies within object_radius of the origin, and the field's box is that
  // sphere's cube instead of every frustum (scene_box.h). 0: not a centred rig.
  bool transparent = false;
  double object_radius = 0;

  int frame_count() const { return static_cast<int>(cameras.size()); }
  bool has_depth() const { return !depth.empty(); }
  bool has_masks() const { return !tool_mask.empty(); }
  bool has_stereo() const { return !right_rgb.empty(); }
};

}  // namespace endorecon::scene
