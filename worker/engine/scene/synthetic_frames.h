// The synthetic clip's frames rendered in memory, and the whole clip as a Clip without files: for
// the GPU tests and benchmarks, whose binaries travel to bare GPU machines and so link no image or
// video codec (scripts/gpu-check). synthetic_clip.h writes the same frames as files.
#pragma once

#include <cstdint>
#include <vector>

#include "worker/engine/scene/clip.h"
#include "worker/engine/scene/synthetic_scene.h"

namespace endorecon::scene {

// One frame as the clip's files hold it: row-major, top row first, colour in RGB order.
struct SyntheticFrame {
  std::vector<std::uint8_t> rgb;        // what the camera saw (tool, exposure, camera noise)
  std::vector<std::uint8_t> gt_rgb;     // the tissue alone, with the exposure, without noise
  std::vector<std::uint8_t> right_rgb;  // the right eye's view [stereo]
  std::vector<std::uint8_t> depth;      // stereo-like 8-bit z-depth, 0 = hole
  std::vector<std::uint8_t> tool_mask;  // 255 where the tool is seen
  std::vector<float> gt_depth;          // the tissue's z-depth
};

// Throws FailInvalid naming what is wrong with `options`.
void CheckSynthOptions(const SynthOptions& options);

// Frame `index` of the clip `options` describe (deterministic: the same options, the same bytes).
SyntheticFrame RenderSyntheticFrame(const SyntheticScene& scene, const SynthOptions& options, int index);

// The clip exactly as scene::LoadClip reads what WriteSyntheticClip writes (cameras, times, near and
// far, frames, depth, masks, the right eye, the ground truth), made in memory. Throws as
// CheckSynthOptions; a recording (`options.recording`) is files only and is not made.
Clip MakeSyntheticClip(const SynthOptions& options);

}  // namespace endorecon::scene
