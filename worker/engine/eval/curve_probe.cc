#include "worker/engine/eval/curve_probe.h"

#include <algorithm>

#include "worker/engine/eval/depth_error.h"
#include "worker/engine/eval/evaluation_mask.h"
#include "worker/engine/eval/image_metrics.h"
#include "worker/engine/eval/strided_map.h"
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
  const int w = clip_.width, h = clip_.height;
  const int stride = StrideFor(w, h, kMaxPixels, 2);
  const std::vector<int> picked = StridedPixels(w, h, stride);
  const int n = int(picked.size()), gw = GridSize(w, stride), gh = GridSize(h, stride);
  std::vector<float> rgb(3 * std::size_t(n)), depth(n), opacity(n);
  std::vector<double> psnr, depth_rmse;
  for (int f : frames_) {
    renderer.RenderPixels(clip_.cameras[f], clip_.times[f], picked.data(), n,
                          {rgb.data(), depth.data(), opacity.data()});
    const auto mask = Gather<std::uint8_t>(EvaluationMask(clip_, f), picked);
    psnr.push_back(
        MeasureImage(rgb, Gather<std::uint8_t>(clip_.rgb[f], picked, 3), mask, gw, gh).psnr_tissue);
    if (!clip_.gt_depth.empty()) {
      depth_rmse.push_back(
          MeasureDepth(depth, Gather<float>(clip_.gt_depth[f], picked), mask, gw, gh, clip_.near, clip_.far)
              .rmse_relative);
    }
  }
  Point point;
  point.psnr = Summarise(psnr).mean;
  if (!depth_rmse.empty()) point.depth_rmse = Summarise(depth_rmse).mean;
  return point;
}

}  // namespace endorecon::eval
