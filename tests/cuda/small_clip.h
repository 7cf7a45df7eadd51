// The small clip the GPU tests train and render on, made in memory (no image files: the GPU test
// binary travels to bare GPU machines, scripts/gpu-check): synth's defaults at 8 frames of 48 x 40.
#pragma once

#include "worker/engine/scene/synthetic_frames.h"

namespace endorecon::cuda {

inline scene::Clip SmallClip() {
  scene::SynthOptions synth;
  synth.frames = 8;
  synth.width = 48;
  synth.height = 40;
  return scene::MakeSyntheticClip(synth);
}

}  // namespace endorecon::cuda
