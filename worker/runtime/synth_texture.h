// The picture `endorecon-worker synth --texture` maps onto the synthetic tissue (SynthOptions::texture).
#pragma once

#include <string>

#include "worker/engine/scene/synthetic_scene.h"

namespace endorecon::worker {

// An image file as it is, or frame `index` of a video or image folder (-1: the middle one) cropped
// to a centred square of 70% of its shorter side (an endoscope sees a circle; its centre is tissue).
// Sets options.texture, texture_width, texture_height and texture_source. Throws Error naming the
// file when it cannot be read or has no such frame.
void LoadSynthTexture(const std::string& path, int index, scene::SynthOptions& options);

}  // namespace endorecon::worker
