// The error-against-run-time curve's measurement: held-out tissue PSNR (and depth error against the
// clip's ground truth, where it has one) over a few held-out frames, cheap enough to take every few
// seconds of a run: every s-th pixel of every s-th row, s = 2 or more so a frame gives at most
// kMaxPixels (a quarter of a demo clip's frame, 1/25 of a 640 x 512 one; the final evaluation
// measures every pixel).
#pragma once

#include <vector>

#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/scene/clip.h"

namespace endorecon::eval {

class CurveProbe {
 public:
  // At most `max_frames` of `heldout`, evenly spread. The clip must outlive the probe.
  CurveProbe(const scene::Clip& clip, const std::vector<int>& heldout, int max_frames);
  bool empty() const { return frames_.empty(); }

  struct Point {
    double psnr = 0;
    double depth_rmse = -1;  // relative to far - near; -1 without ground-truth depth
  };

  // Means over the probe frames where the value is defined (an all-tool frame has no tissue PSNR).
  Point Measure(render::FrameRenderer& renderer) const;

  static constexpr int kMaxPixels = 20000;

 private:
  const scene::Clip& clip_;
  std::vector<int> frames_;
};

}  // namespace endorecon::eval
