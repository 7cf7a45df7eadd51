// An object capture for tests of object scenes: `synth --object` (square views of `size` pixels, on
// transparency or, with a backdrop, opaque) written to `dir` and loaded back as a user's would be.
#pragma once

#include <filesystem>

#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/synthetic_object.h"

namespace endorecon::testing {

inline scene::Clip ObjectClip(const std::filesystem::path& dir, int views, int size, bool backdrop = false) {
  scene::ObjectSynthOptions synth;
  synth.views = views;
  synth.width = synth.height = size;
  synth.backdrop = backdrop;
  scene::WriteSyntheticObject(synth, dir);
  return scene::LoadClip(dir);
}

}  // namespace endorecon::testing
