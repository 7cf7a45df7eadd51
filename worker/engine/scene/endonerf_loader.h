// The EndoNeRF layout: images/, optional depth/, masks/ (255 = tool), gt_masks/, images_right/
// (+ stereo.json), and poses_bounds.npy (N x 17 float64 rows: a 3x5 [R | t | (H, W, f)] in LLFF's
// [down, right, back] column order, then near and far). See docs/formats.md.
#pragma once

#include <filesystem>

#include "worker/engine/scene/clip.h"
#include "worker/engine/scene/load_options.h"

namespace endorecon::scene {

// The right eye's offset along the left camera's x axis when images_right/ has no stereo.json,
// in clip units (about a stereo endoscope's 5 mm if a unit is a millimetre).
inline constexpr double kDefaultStereoBaseline = 5.0;

// Loads and validates the clip in `dir`. Files of each folder are taken in sorted order, times are
// evenly spaced in [0, 1] (0 for a single frame), near/far are the smallest near and largest far
// over the rows, cx = W/2, cy = H/2, fx = fy = f. Images smaller than the pose file's H x W by one
// factor scale f by it. Throws Error naming the file and what is wrong (docs/formats.md).
Clip LoadEndoNerfClip(const std::filesystem::path& dir, const LoadOptions& options);

}  // namespace endorecon::scene
