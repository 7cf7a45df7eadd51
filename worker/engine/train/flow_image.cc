#include "worker/engine/train/flow_image.h"

#include <opencv2/imgproc.hpp>

namespace endorecon::train {
namespace {

// Grey levels at or above this are taken for specular highlights, which move with the light.
constexpr int kSaturated = 250;

}  // namespace

FlowImage FlowImageOf(const scene::Clip& clip, int f, cv::Size size, double mean) {
  const cv::Mat rgb(clip.height, clip.width, CV_8UC3, const_cast<std::uint8_t*>(clip.rgb[f].data()));
  FlowImage image;
  cv::Mat grey;
  cv::cvtColor(rgb, grey, cv::COLOR_RGB2GRAY);
  if (size != grey.size()) cv::resize(grey, grey, size, 0, 0, cv::INTER_AREA);
  const double own = cv::mean(grey)[0];
  if (mean > 0 && own > 0) grey.convertTo(grey, CV_8U, mean / own);
  image.grey = grey;
  image.usable = grey < kSaturated;
  if (clip.has_masks()) {
    const cv::Mat tool(clip.height, clip.width, CV_8U, const_cast<std::uint8_t*>(clip.tool_mask[f].data()));
    // The block's share of tool pixels, in floats: any tool pixel makes it nonzero (the mask's 0/1
    // bytes averaged would round a block less than half tool to 0, and its edge's motion is the tool's).
    cv::Mat share;
    cv::Mat(tool != 0).convertTo(share, CV_32F);
    if (size != share.size()) cv::resize(share, share, size, 0, 0, cv::INTER_AREA);
    image.usable &= share == 0;
  }
  image.usable /= 255;
  return image;
}

}  // namespace endorecon::train
