// EndoNeRF's refinement of the depth priors during training (design note, "Depth refinement"; the
// paper: every K = 4000 iterations, with an exponential moving average, alpha = 0.1). Stereo depth
// is noisy; a field trained on it fits the noise. Every so often each training frame is rendered at
// its measured tissue pixels by the frame renderer (which never reads priors, so a wrong prior cannot
// steer its own correction), and in each frame the `fraction` of pixels whose prior disagrees most
// with the rendering move towards it: prior <- (1 - ema) prior + ema rendered (ema = 1 is EndoNeRF's
// outright replacement). Pixels without a prior (0: holes) and tool pixels are never touched, so the
// depth loss still only supervises where the clip measured something, or where a hole was filled from
// the measurements around it when the refiner was made (depth_fill.h).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <iosfwd>
#include <vector>

#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/scene/clip.h"

namespace endorecon::train {

struct DepthRefineStats {
  std::size_t measured = 0;  // measured tissue pixels rendered
  std::size_t moved = 0;     // priors changed
  double mean_shift = 0;     // mean |change| of those, clip units
};

class DepthRefiner {
 public:
  // clip must outlive the refiner; frames: the training frames (only they are rendered and refined).
  // fill_sigma > 0: the training frames' holes are filled first (FillDepthHoles with that sigma).
  DepthRefiner(const scene::Clip& clip, std::vector<int> frames, double fill_sigma = 0);

  // Hole pixels the fill gave a prior, and those it left, over the training frames.
  std::size_t filled() const { return filled_; }
  std::size_t left() const { return left_; }

  // The current prior of a pixel: the clip's (its holes filled) until its frame is first refined.
  // 0 = unknown.
  float Prior(int frame, int pixel) const { return PriorFrame(frame)[std::size_t(pixel)]; }

  // The current priors of a whole frame (H x W), as Prior reads them; valid until the next round or Load.
  const float* PriorFrame(int frame) const {
    const auto& refined = refined_[std::size_t(frame)];
    return refined.empty() ? Unrefined(frame).data() : refined.data();
  }

  // One round; fraction in (0, 1], ema in (0, 1]. No-op without depth. A round refines the training
  // frames in turn, starting where the last round stopped, until max_pixels measured pixels were
  // rendered (at least one frame; 0: every training frame once, as EndoNeRF), so a round's cost is
  // bounded however long the clip is.
  DepthRefineStats Refine(render::FrameRenderer& renderer, float fraction, float ema,
                          std::size_t max_pixels = 0);
  int rounds() const { return rounds_; }
  // Counts the rounds up to `rounds` whose time passed with the one just made (Trainer::Step).
  void CatchUp(int rounds) { rounds_ = std::max(rounds_, rounds); }

  // Exact state for resume (the refined frames, the round count and where the next round starts). Load throws
  // Error(kDataLoss) for a truncated stream or one of another clip size.
  void Save(std::ostream& out) const;
  void Load(std::istream& in);

 private:
  const scene::Clip& clip_;
  std::vector<int> frames_;
  // The prior a frame starts from: the clip's, or its filled copy.
  const std::vector<float>& Unrefined(int frame) const {
    const auto& filled = filled_frames_[std::size_t(frame)];
    return filled.empty() ? clip_.depth[std::size_t(frame)] : filled;
  }

  std::vector<std::vector<float>> refined_;  // per frame of the clip; empty until that frame is refined
  // Per frame of the clip, the prior with its holes filled; empty where nothing was filled. Derived
  // from the clip and fill_sigma when the refiner is made, so not in the checkpoint (every training
  // frame's prior in every checkpoint would be 1.3 MB a frame at 640 x 512).
  std::vector<std::vector<float>> filled_frames_;
  int rounds_ = 0;
  std::size_t filled_ = 0, left_ = 0;
  std::size_t next_ = 0;  // index into frames_ of the frame the next round starts with
};

}  // namespace endorecon::train
