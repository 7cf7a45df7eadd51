// The transforms.json layout of instant-ngp and nerfstudio: intrinsics at the top level (optionally
// overridden per frame), and per frame a file_path and a 4x4 camera-to-world transform_matrix in the
// OpenGL convention, with optional time, depth_file_path and mask_path. See docs/formats.md.
#pragma once

#include <filesystem>

#include "worker/engine/scene/clip.h"
#include "worker/engine/scene/load_options.h"

namespace endorecon::scene {

// Loads and validates `dir`/transforms.json and the files it names (paths relative to `dir`, with or
// without an image extension). Focal length from fl_x/fl_y or camera_angle_x/camera_angle_y; cx, cy
// default to the image centre; w, h default to the first image's size. Distortion fields are ignored
// with a warning. Masks follow nerfstudio (0 = excluded, i.e. tool). Frames keep the file's order.
// No "time" anywhere: a static clip with times 0; times outside [0, 1] are rescaled to it.
// near/far: the top-level "near"/"far", otherwise 0.8 x the smallest and 1.2 x the largest depth
// value, otherwise 0.05 and 2.5 x the median camera distance from the origin. A centred rig (every
// camera looking at the origin, from directions spread at least 30 degrees about their mean: an object
// capture) sets clip.object_radius to half the median camera distance, and without near/far or depth
// its near/far are the nearest camera's distance less that radius and the farthest one's plus it.
// RGBA images are composited onto LoadOptions::alpha_background (white: NeRF-synthetic's convention).
// Throws Error naming the file, the frame and what is wrong.
Clip LoadTransformsClip(const std::filesystem::path& dir, const LoadOptions& options);

}  // namespace endorecon::scene
