#include "worker/prepare/preview_image.h"

#include <algorithm>
#include <opencv2/imgproc.hpp>

namespace endorecon::prepare {

cv::Mat PreviewImage(const cv::Mat& frame, const cv::Mat& depth, const cv::Mat& excluded, double near,
                     double far) {
  cv::Mat scaled, colour;
  depth.convertTo(scaled, CV_8U, 255.0 / std::max(1e-9, far - near),
                  -255.0 * near / std::max(1e-9, far - near));
  cv::applyColorMap(scaled, colour, cv::COLORMAP_INFERNO);
  colour.setTo(cv::Scalar::all(0), depth <= 0);

  cv::Mat overlay = frame.clone();
  if (!excluded.empty()) {
    cv::Mat tint(frame.size(), frame.type(), cv::Scalar(255, 64, 0));
    cv::Mat blended;
    cv::addWeighted(frame, 0.45, tint, 0.55, 0, blended);
    blended.copyTo(overlay, excluded);
  }

  cv::Mat panels;
  cv::hconcat(std::vector<cv::Mat>{frame, colour, overlay}, panels);
  if (panels.rows > 360) {
    cv::resize(panels, panels, cv::Size(), 360.0 / panels.rows, 360.0 / panels.rows, cv::INTER_AREA);
  }
  return panels;
}

}  // namespace endorecon::prepare
