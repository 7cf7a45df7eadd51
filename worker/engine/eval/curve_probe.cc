#include "worker/engine/eval/curve_probe.h"

#include <algorithm>

#include "worker/engine/eval/clip_evaluator.h"
#include "worker/engine/eval/depth_error.h"
#include "worker/engine/eval/image_metrics.h"
#include "worker/engine/eval/summary.h"

namespace endorecon::eval {

CurveProbe::CurveProbe(const scene::Clip& clip, const std::vector<int>& heldout, int max_frames)
    : clip_(clip) {
  const int step = std::max<int>(1, int(heldout.size()) / std::max(1, max_frames));
  for (std::size_t i = 0; i < heldout.size() && int(frames_.size()) < max_frames; i += step) {
    frames_.push_back(heldout[i]);
  }
}

CurveProbe::Point CurveProbe::Measure(render::FrameRenderer& renderer) const {
  std::vector<double> psnr, depth;
  for (int f : frames_) {
    const auto frame = renderer.Render(clip_.cameras[f], clip_.times[f]);
    const auto& mask = EvaluationMask(clip_, f);
    psnr.push_back(MeasureImage(frame.rgb, clip_.rgb[f], mask, clip_.width, clip_.height).psnr_tissue);
    if (!clip_.gt_depth.empty()) {
      depth.push_back(
          MeasureDepth(frame.depth, clip_.gt_depth[f], mask, clip_.width, clip_.height, clip_.near, clip_.far)
              .rmse_relative);
    }
  }
  Point point;
  point.psnr = Summarise(psnr).mean;
  if (!depth.empty()) point.depth_rmse = Summarise(depth).mean;
  return point;
}

}  // namespace endorecon::eval
