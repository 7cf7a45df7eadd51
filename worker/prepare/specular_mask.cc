#include "worker/prepare/specular_mask.h"

#include <opencv2/imgproc.hpp>

namespace endorecon::prepare {

cv::Mat SpecularMask(const cv::Mat& bgr, int min_channel, int grow) {
  cv::Mat mask;
  cv::inRange(bgr, cv::Scalar::all(min_channel), cv::Scalar::all(255), mask);
  if (grow > 0) {
    cv::dilate(mask, mask,
               cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(2 * grow + 1, 2 * grow + 1)));
  }
  return mask;
}

}  // namespace endorecon::prepare
