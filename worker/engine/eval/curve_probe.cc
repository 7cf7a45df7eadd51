#include "worker/engine/eval/curve_probe.h"

#include <algorithm>

#include "worker/engine/eval/clip_evaluator.h"
#include "worker/engine/eval/depth_error.h"
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
  int stride = 2;
  while (GridSize(w, stride) * GridSize(h, stride) > kMaxPixels) ++stride;
  const std::vector<int> picked = StridedPixels(w, h, stride);
  const int n = int(picked.size()), gw = GridSize(w, stride), gh = GridSize(h, stride);
  std::vector<float> rgb(3 * std::size_t(n)), depth(n), opacity(n), truth_depth(n);
  std::vector<std::uint8_t> truth_rgb(3 * std::size_t(n));
  std::vector<std::uint8_t> mask;
  std::vector<double> psnr, depth_rmse;
  for (int f : frames_) {
    renderer.RenderPixels(clip_.cameras[f], clip_.times[f], picked.data(), n,
                          {rgb.data(), depth.data(), opacity.data()});
    const auto& full_mask = EvaluationMask(clip_, f);
    mask.assign(full_mask.empty() ? 0 : n, 0);
    for (int i = 0; i < n; ++i) {
      const std::size_t p = std::size_t(picked[i]);
      for (int c = 0; c < 3; ++c) truth_rgb[3 * std::size_t(i) + c] = clip_.rgb[f][3 * p + c];
      if (!full_mask.empty()) mask[i] = full_mask[p];
      if (!clip_.gt_depth.empty()) truth_depth[i] = clip_.gt_depth[f][p];
    }
    psnr.push_back(MeasureImage(rgb, truth_rgb, mask, gw, gh).psnr_tissue);
    if (!clip_.gt_depth.empty()) {
      depth_rmse.push_back(MeasureDepth(depth, truth_depth, mask, gw, gh, clip_.near, clip_.far).rmse_relative);
    }
  }
  Point point;
  point.psnr = Summarise(psnr).mean;
  if (!depth_rmse.empty()) point.depth_rmse = Summarise(depth_rmse).mean;
  return point;
}

}  // namespace endorecon::eval
