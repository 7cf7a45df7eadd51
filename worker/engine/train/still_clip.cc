#include "worker/engine/train/still_clip.h"

#include <algorithm>
#include <cmath>
#include <opencv2/video/tracking.hpp>

#include "worker/engine/train/flow_image.h"

namespace endorecon::train {
namespace {

// Fewer usable pixels than this in a frame say nothing of its motion (a frame that is all tool).
constexpr int kLeastPixels = 64;

}  // namespace

Stillness MeasureStillness(const scene::Clip& clip, const std::vector<int>& frames, double threshold_px) {
  Stillness s;
  if (frames.size() < 2) {
    s.why = "fewer than two training frames";
    return s;
  }
  if (clip.rgb.empty()) {
    s.why = "the clip has no images";
    return s;
  }
  std::vector<int> order = frames;
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) { return clip.times[a] < clip.times[b]; });
  const int ref = order.front();
  for (int f : order) {
    if (clip.cameras[f].c2w != clip.cameras[ref].c2w) {
      s.why = "the camera moves";
      return s;
    }
  }
  const int factor = (clip.width + kStillFlowWidth - 1) / kStillFlowWidth;
  const cv::Size size(clip.width / factor, clip.height / factor);
  if (size.width < kLeastFlowSide || size.height < kLeastFlowSide) {
    s.why = "frames too small for optical flow";
    return s;
  }
  s.tested = true;
  const FlowImage ref_image = FlowImageOf(clip, ref, size, 0);
  const double ref_mean = cv::mean(ref_image.grey)[0];
  cv::Ptr<cv::DISOpticalFlow> dis = cv::DISOpticalFlow::create(cv::DISOpticalFlow::PRESET_MEDIUM);
  std::vector<float> moved;
  for (auto it = order.rbegin(); it != order.rend() && *it != ref; ++it) {
    const FlowImage image = FlowImageOf(clip, *it, size, ref_mean);
    cv::Mat flow;
    dis->calc(ref_image.grey, image.grey, flow);
    moved.clear();
    for (int y = 0; y < size.height; ++y) {
      for (int x = 0; x < size.width; ++x) {
        if (!ref_image.usable.at<std::uint8_t>(y, x) || !image.usable.at<std::uint8_t>(y, x)) continue;
        const cv::Vec2f d = flow.at<cv::Vec2f>(y, x);
        moved.push_back(std::hypot(d[0], d[1]) * float(factor));
      }
    }
    if (moved.size() < std::size_t(kLeastPixels)) continue;
    const auto p95 = moved.begin() + std::ptrdiff_t(0.95 * double(moved.size() - 1));
    std::nth_element(moved.begin(), p95, moved.end());
    s.motion_px = std::max(s.motion_px, double(*p95));
    ++s.frames;
    if (!(*p95 < threshold_px)) return s;  // NaN flow counts as motion
  }
  if (s.frames == 0) {
    s.tested = false;
    s.why = "no frame has enough pixels without tool to tell";
    return s;
  }
  s.still = true;
  return s;
}

}  // namespace endorecon::train
