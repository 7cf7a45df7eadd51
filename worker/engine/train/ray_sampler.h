// Picks training rays (frame, pixel) by EndoNeRF's tool-mask importance: never a tool pixel, and
// tissue that is often hidden by the tool is drawn more often (weight 1 + how often the pixel is
// tool across the clip, normalised to [1, 2]). A clip without masks draws pixels uniformly.
// Rejection sampling against the bound 2: no per-frame tables, so memory stays at one float per
// pixel however long the clip is.
#pragma once

#include <cstdint>
#include <vector>

#include "worker/engine/scene/clip.h"

namespace endorecon::train {

struct RayPick {
  int frame = 0;
  int pixel = 0;  // row-major index y * width + x
};

class RaySampler {
 public:
  // `frames`: the frames rays may come from (the training split). Frames with no tissue pixel
  // are left out; throws Error(kInvalidArgument) when no frame has any.
  RaySampler(const scene::Clip& clip, std::vector<int> frames);

  // A pick that is a pure function of (seed, stream): deterministic in any order, on any thread.
  RayPick Pick(std::uint64_t seed, std::uint64_t stream) const;

  const std::vector<int>& frames() const { return frames_; }
  // Weight of a pixel in a frame (0 on tool pixels), for tests and for blending other importance maps.
  float Weight(int frame, int pixel) const;

 private:
  const scene::Clip& clip_;
  std::vector<int> frames_;
  std::vector<float> occlusion_weight_;  // per pixel, in [1, 2]; empty without masks
};

}  // namespace endorecon::train
