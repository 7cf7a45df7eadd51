// What a transforms.json says beyond its files: each frame's camera, the frames' times, near/far and
// whether the cameras stand around an object (a centred rig). Shared by the loader, which reads the
// images first (transforms_loader.h), and by captures made in memory (synthetic_object.h), so that
// both give the same Clip. No image is read or decoded here.
#pragma once

#include <nlohmann/json_fwd.hpp>
#include <string>

#include "worker/engine/scene/clip.h"

namespace endorecon::scene {

// Sets clip.cameras, times, is_static (no "time" anywhere), near, far and object_radius from `top`
// (the whole transforms.json) for a clip whose size (clip.width, clip.height) and depth maps, if any,
// are already set; the rules are LoadTransformsClip's (transforms_loader.h). `file` names the JSON in
// messages. Throws Error naming the file, the frame and what is wrong.
void FinishTransformsClip(const nlohmann::json& top, const std::string& file, Clip& clip);

}  // namespace endorecon::scene
