// Rectification of a stereo recording: both eyes re-imaged by one pinhole camera (no
// distortion, rows aligned, zero disparity at infinity) whose principal point is the frame's
// centre, cropped to what both eyes fill. The geometry is chosen once per recording.
#pragma once

#include <opencv2/core.hpp>
#include <vector>

#include "worker/prepare/stereo_calibration.h"

namespace endorecon::prepare {

// The rectified pair's camera. Principal point: the centre, (W - 1) / 2 and (H - 1) / 2 in
// OpenCV's pixel convention, W / 2 and H / 2 in endorecon's (pixel centres at + 0.5).
struct RectifiedCamera {
  cv::Size size;
  double focal = 0;     // pixels, both eyes
  double baseline = 0;  // the right eye's offset along x, calibration units
  // Rotations from each raw eye's camera frame to its rectified one (stereoRectify's R1, R2).
  cv::Matx33d left_rotation = cv::Matx33d::eye(), right_rotation = cv::Matx33d::eye();
  double scale = 1;  // the output's focal length over the source's (mean of the eyes'): < 1 shrinks

  cv::Matx33d Matrix() const {
    return {focal, 0, (size.width - 1) / 2.0, 0, focal, (size.height - 1) / 2.0, 0, 0, 1};
  }
};

class StereoRectifier {
 public:
  // stereoRectify (CALIB_ZERO_DISPARITY) on `calibration`, then the largest window centred on the
  // principal point inside which both eyes have pixels, of `output`'s aspect (0x0: the eyes'
  // aspect), scaled to `output` (0x0: the source's focal length, sizes rounded down to even).
  // An already rectified calibration at its own size passes frames through untouched.
  // Throws FailInvalid when the eyes share no valid window (a calibration of another rig).
  StereoRectifier(const StereoCalibration& calibration, cv::Size output);

  const RectifiedCamera& camera() const { return camera_; }
  bool passthrough() const { return passthrough_; }

  // One raw eye's 8-bit image (any channels) rectified: bilinear, area-averaged from a finer
  // rectification when the output shrinks the source by 2 or more.
  cv::Mat Left(const cv::Mat& image) const { return Apply(image, 0); }
  cv::Mat Right(const cv::Mat& image) const { return Apply(image, 1); }
  // A 0/255 mask of the raw left (right) eye carried the same way, 255 where the result is >= 128.
  cv::Mat LeftMask(const cv::Mat& mask) const { return Binary(Apply(mask, 0)); }
  cv::Mat RightMask(const cv::Mat& mask) const { return Binary(Apply(mask, 1)); }

  // Raw pixel positions of eye 0 (left) or 1 (right) in rectified pixels (OpenCV's convention).
  std::vector<cv::Point2d> RectifyPoints(int eye, const std::vector<cv::Point2d>& raw) const;

 private:
  cv::Mat Apply(const cv::Mat& image, int eye) const;
  static cv::Mat Binary(const cv::Mat& mask);

  StereoCalibration calibration_;
  RectifiedCamera camera_;
  bool passthrough_ = false;
  int supersample_ = 1;        // rectify at this multiple of the output size, then area-average
  cv::Mat map1_[2], map2_[2];  // remap tables (CV_16SC2 + CV_16UC1) at supersample_ x the output
};

}  // namespace endorecon::prepare
