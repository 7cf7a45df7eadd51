#include "worker/engine/train/depth_fill.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>
#include <string>

#include "common/error.h"
#include "worker/engine/train/losses.h"

namespace endorecon::train {

FilledDepth FillDepthHoles(std::span<const float> depth, std::span<const std::uint8_t> tool_mask, int width,
                           int height, double sigma) {
  const std::size_t n = std::size_t(std::max(width, 0)) * std::size_t(std::max(height, 0));
  if (width <= 0 || height <= 0 || depth.size() != n || (!tool_mask.empty() && tool_mask.size() != n) ||
      !(sigma >= 0)) {
    FailInvalid("FillDepthHoles: a " + std::to_string(width) + " x " + std::to_string(height) + " frame with " +
                std::to_string(depth.size()) + " depths, " + std::to_string(tool_mask.size()) +
                " mask values and sigma " + std::to_string(sigma));
  }
  FilledDepth out;
  out.depth.assign(depth.begin(), depth.end());
  cv::Mat measured(height, width, CV_32F), weighted(height, width, CV_32F);
  for (std::size_t p = 0; p < n; ++p) {
    const bool known = HasDepthPrior(depth[p]);
    measured.at<float>(int(p)) = known ? 1.0f : 0.0f;
    weighted.at<float>(int(p)) = known ? depth[p] : 0.0f;
    if (!known) out.depth[p] = 0.0f;
  }
  cv::Mat near_tool = cv::Mat::zeros(height, width, CV_8U);
  if (!tool_mask.empty()) {
    const cv::Mat tool(height, width, CV_8U, const_cast<std::uint8_t*>(tool_mask.data()));
    cv::dilate(tool != 0, near_tool, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(7, 7)));
  }
  cv::Mat sum_depth, sum_weight;
  if (sigma > 0) {
    // OpenCV's separable blur, zero outside the frame: the weights then count only what was measured.
    cv::GaussianBlur(weighted, sum_depth, cv::Size(0, 0), sigma, sigma, cv::BORDER_CONSTANT);
    cv::GaussianBlur(measured, sum_weight, cv::Size(0, 0), sigma, sigma, cv::BORDER_CONSTANT);
  }
  for (std::size_t p = 0; p < n; ++p) {
    if (measured.at<float>(int(p)) > 0) continue;
    const float weight = sigma > 0 ? sum_weight.at<float>(int(p)) : 0.0f;
    if (weight >= 0.05f && near_tool.at<std::uint8_t>(int(p)) == 0) {
      out.depth[p] = sum_depth.at<float>(int(p)) / weight;
      ++out.filled;
    } else {
      ++out.left;
    }
  }
  return out;
}

}  // namespace endorecon::train
