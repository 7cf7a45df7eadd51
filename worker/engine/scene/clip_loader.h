// The one entry point for reading a clip from disk, whatever its layout.
#pragma once

#include <filesystem>

#include "worker/engine/scene/clip.h"
#include "worker/engine/scene/load_options.h"

namespace endorecon::scene {

// Loads and validates the clip in `dir`: the transforms.json layout when `dir`/transforms.json
// exists, else the EndoNeRF layout when `dir`/poses_bounds.npy exists. Ground truth in `dir`/gt/
// (images/ of tool-free frames, depth/ of float z-depth .npy files, one per frame; written by the
// synthetic generator) fills Clip::gt_rgb / gt_depth. Throws Error(kNotFound) when `dir` does not
// exist, and Error(kInvalidArgument or kResourceExhausted) naming the file and the fault otherwise.
Clip LoadClip(const std::filesystem::path& dir, const LoadOptions& options = {});

}  // namespace endorecon::scene
