#include "worker/engine/scene/outside_view.h"

#include <algorithm>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.h"

namespace endorecon::scene {

std::vector<std::uint8_t> OutsideViewMask(const std::vector<cv::Mat>& frames, int max_level) {
  if (frames.empty()) return {};
  const int w = frames[0].cols, h = frames[0].rows;
  const std::size_t pixels = std::size_t(w) * h;
  // Dark in every frame: the brightest channel's maximum over frames.
  cv::Mat dark(h, w, CV_8U, cv::Scalar(1));
  for (const cv::Mat& frame : frames) {
    if (frame.type() != CV_8UC3 || frame.size() != dark.size() || !frame.isContinuous())
      FailInvalid("outside view: frames must be 8-bit, 3 channels, one size");
    std::uint8_t* d = dark.ptr<std::uint8_t>();
    const std::uint8_t* c = frame.ptr<std::uint8_t>();
    for (std::size_t p = 0; p < pixels; ++p, c += 3) {
      if (c[0] > max_level || c[1] > max_level || c[2] > max_level) d[p] = 0;
    }
  }
  // The dark regions that reach the edge (OpenCV's labelling rather than a hand-written fill).
  cv::Mat labels;
  const int count = cv::connectedComponents(dark, labels, 4, CV_32S);
  std::vector<std::uint8_t> at_edge(std::size_t(count), 0);
  for (int x = 0; x < w; ++x) at_edge[labels.at<int>(0, x)] = at_edge[labels.at<int>(h - 1, x)] = 1;
  for (int y = 0; y < h; ++y) at_edge[labels.at<int>(y, 0)] = at_edge[labels.at<int>(y, w - 1)] = 1;
  std::vector<std::uint8_t> mask(pixels, 0);
  std::size_t outside = 0;
  const int* label = labels.ptr<int>();
  const std::uint8_t* d = dark.ptr<std::uint8_t>();
  for (std::size_t p = 0; p < pixels; ++p) {
    mask[p] = d[p] != 0 && at_edge[std::size_t(label[p])] ? 1 : 0;
    outside += mask[p];
  }
  // A scope's view is most of the frame; a frame dark nearly everywhere (a lens cap, an unlit
  // scene) has no view to keep, and is left as it is.
  if (outside == 0 || outside > pixels * 3 / 4) return {};
  return mask;
}

std::vector<std::uint8_t> OutsideViewMask(const Clip& clip, int max_level) {
  std::vector<cv::Mat> frames;  // headers over the clip's pixels, not copies
  for (const auto& frame : clip.rgb)
    frames.emplace_back(clip.height, clip.width, CV_8UC3, const_cast<std::uint8_t*>(frame.data()));
  return OutsideViewMask(frames, max_level);
}

int RenderedPixels(const Clip& clip) {
  return clip.width * clip.height - int(std::count(clip.outside_view.begin(), clip.outside_view.end(), 1));
}

void ExcludeFromFrames(Clip& clip, const std::vector<std::uint8_t>& mask) {
  const std::size_t pixels = std::size_t(clip.width) * clip.height;
  if (mask.size() != pixels) {
    FailInvalid(clip.source + ": a mask of " + std::to_string(mask.size()) + " pixels for frames of " +
                std::to_string(pixels));
  }
  if (clip.tool_mask.empty())
    clip.tool_mask.assign(std::size_t(clip.frame_count()), std::vector<std::uint8_t>(pixels, 0));
  clip.outside_view = mask;
  for (auto* masks : {&clip.tool_mask, &clip.eval_mask}) {
    for (auto& frame : *masks) {
      for (std::size_t p = 0; p < pixels; ++p) frame[p] = frame[p] | mask[p];
    }
  }
}

}  // namespace endorecon::scene
