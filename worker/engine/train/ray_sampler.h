// Picks training rays (frame, pixel) by EndoNeRF's tool-mask importance: never a tool pixel, and
// tissue that is often hidden by the tool is drawn more often (weight 1 + how often the pixel is
// tool across the clip, normalised to [1, 2]). A clip without masks draws pixels uniformly.
// Rejection sampling against the bound 2: no per-frame tables, so memory stays at one float per
// pixel however long the clip is.
#pragma once

#include <cstdint>
#include <vector>

#include "worker/engine/scene/clip.h"
#include "worker/engine/train/ray_picks.h"

namespace endorecon::train {

class RaySampler {
 public:
  // `frames`: the frames rays may come from (the training split). Frames with no tissue pixel
  // are left out; throws Error(kInvalidArgument) when no frame has any.
  RaySampler(const scene::Clip& clip, std::vector<int> frames);
  RaySampler(const RaySampler&) = delete;  // tables() points into it
  RaySampler& operator=(const RaySampler&) = delete;

  // A pick that is a pure function of (seed, stream): deterministic in any order, on any thread
  // (PickRay over tables()).
  RayPick Pick(std::uint64_t seed, std::uint64_t stream) const { return PickRay(tables_, seed, stream); }
  // The tables PickRay reads (they point into this sampler and the clip).
  const PickTables& tables() const { return tables_; }

  const std::vector<int>& frames() const { return frames_; }
  // Weight of a pixel in a frame (0 on tool pixels), for tests and for blending other importance maps.
  float Weight(int frame, int pixel) const;

 private:
  std::vector<int> frames_;
  std::vector<float> occlusion_weight_;           // per pixel, in [1, 2]; empty without masks
  std::vector<const std::uint8_t*> mask_frames_;  // per clip frame; empty without masks
  PickTables tables_;
};

}  // namespace endorecon::train
