// A list of cameras to render, each at a time: the transforms.json layout without images
// (top-level intrinsics, per-frame transform_matrix (camera-to-world, OpenGL) and time in [0, 1] (on
// every view or on none: a static scene's views are at t = 0),
// per-frame intrinsics overriding the top level). Units are the clip's own.
#pragma once

#include <filesystem>
#include <vector>

#include "worker/engine/scene/camera.h"

namespace endorecon::scene {

struct CameraAtTime {
  Camera camera;
  float time = 0;
};

// Throws Error(kInvalidArgument) naming the file, the frame and the field that is wrong
// (missing w/h or focal length, a non-finite or non-rigid matrix, a time outside [0, 1], a time on some
// views and not on others; a top-level "time" is every view's), and
// Error(kResourceExhausted) for a view larger than a clip's frames may be (LoadOptions).
std::vector<CameraAtTime> ReadCameraList(const std::filesystem::path& path);

}  // namespace endorecon::scene
