// Object captures with known truth, written as NeRF-synthetic writes them (transforms.json with
// camera_angle_x, RGBA PNGs whose background is transparent): a textured object at the origin (a
// banded sphere on a checkered pedestal with a small red ball), lit by a fixed light (Lambert, no
// view-dependent shading), seen by cameras at 4 units from the origin on its upper hemisphere, each
// looking at the origin (Blender's z-up world, as NeRF's lego). Edges are anti-aliased (3 x 3 rays a
// pixel; alpha is the share that hit). The object lies within 1.9 units of the origin.
#pragma once

#include <cstdint>
#include <filesystem>

namespace endorecon::scene {

struct ObjectSynthOptions {
  int views = 100, width = 200, height = 200;
  std::uint64_t seed = 1;  // the camera positions
};

// Writes dir/transforms.json, dir/images/r_NNNNNN.png and dir/synth.json (the options), replacing an
// earlier synthetic clip there (synthetic_files.h ClearSyntheticFolder). Throws Error(kUnavailable)
// naming a file that cannot be written.
void WriteSyntheticObject(const ObjectSynthOptions& options, const std::filesystem::path& dir);

}  // namespace endorecon::scene
