// Object captures with known truth, written as NeRF-synthetic writes them (transforms.json with
// camera_angle_x, RGBA PNGs whose background is transparent): a textured object at the origin (a
// banded sphere on a checkered pedestal with a small red ball), lit by a fixed light (Lambert, no
// view-dependent shading), seen by cameras at 4 units from the origin on its upper hemisphere, each
// looking at the origin (Blender's z-up world, as NeRF's lego). Edges are anti-aliased (3 x 3 rays a
// pixel; alpha is the share that hit). The object lies within 1.9 units of the origin. With a
// backdrop the images are opaque RGB instead: what misses the object sees a colour that depends on
// the direction only (BackdropColor: a room's light, brighter above and toward a window), as a
// capture in front of a real backdrop, whose background neither black nor white fits.
#pragma once

#include <array>
#include <cstdint>
#include <filesystem>
#include <nlohmann/json_fwd.hpp>
#include <vector>

#include "worker/engine/scene/clip.h"

namespace endorecon::scene {

struct ObjectSynthOptions {
  int views = 100, width = 200, height = 200;
  std::uint64_t seed = 1;  // the camera positions
  bool backdrop = false;   // opaque images on BackdropColor instead of RGBA on transparency
};

// The backdrop's RGB in [0, 1] seen along the unit world direction d (x, y, z; z up).
void BackdropColor(const double* d, float* rgb);

// The capture's views rendered in memory (deterministic: the same options, the same bytes): each
// view's camera-to-world (row-major 4 x 4, OpenGL axes) and image (row-major, top row first; RGB with
// a backdrop, else RGBA with straight alpha). Throws FailInvalid for no views or an empty image.
struct SyntheticObjectViews {
  int width = 0, height = 0, channels = 0;  // channels: 3 or 4
  std::vector<std::array<double, 16>> c2w;
  std::vector<std::vector<std::uint8_t>> images;
};
SyntheticObjectViews RenderSyntheticObject(const ObjectSynthOptions& options);

// The capture's transforms.json without file paths: camera_angle_x and each view's transform_matrix.
nlohmann::json SyntheticObjectTransforms(const SyntheticObjectViews& views);

// The capture as a Clip without files, exactly as scene::LoadClip reads what WriteSyntheticObject
// writes (images composited onto `alpha_background`, LoadOptions' default white): for the GPU tests,
// whose binary travels to bare GPU machines without image codecs (scripts/gpu-check).
Clip MakeSyntheticObject(const ObjectSynthOptions& options,
                         const std::array<std::uint8_t, 3>& alpha_background = {255, 255, 255});

// Writes dir/transforms.json, dir/images/r_NNNNNN.png and dir/synth.json (the options), replacing an
// earlier synthetic clip there (synthetic_files.h ClearSyntheticFolder). Throws Error(kUnavailable)
// naming a file that cannot be written. Defined in synthetic_object_files.cc.
void WriteSyntheticObject(const ObjectSynthOptions& options, const std::filesystem::path& dir);

}  // namespace endorecon::scene
