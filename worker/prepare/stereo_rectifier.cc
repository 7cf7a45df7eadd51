#include "worker/prepare/stereo_rectifier.h"

#include <fmt/format.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "common/error.h"

namespace endorecon::prepare {
namespace {

// Canvas pixels where both eyes' remap tables point inside their source images (a bilinear
// sample there reads no border).
cv::Mat ValidInBoth(const StereoCalibration& c, const cv::Mat r[2], const cv::Mat& p, cv::Size size) {
  cv::Mat valid(size, CV_8U, cv::Scalar(1));
  const cv::Matx33d k[2] = {c.k1, c.k2};
  const cv::Mat d[2] = {c.d1, c.d2};
  for (int eye = 0; eye < 2; ++eye) {
    cv::Mat mx, my;
    cv::initUndistortRectifyMap(k[eye], d[eye], r[eye], p, size, CV_32FC1, mx, my);
    for (int y = 0; y < size.height; ++y) {
      const float* xs = mx.ptr<float>(y);
      const float* ys = my.ptr<float>(y);
      std::uint8_t* row = valid.ptr<std::uint8_t>(y);
      for (int x = 0; x < size.width; ++x) {
        row[x] &= xs[x] >= 0 && xs[x] <= size.width - 1 && ys[x] >= 0 && ys[x] <= size.height - 1;
      }
    }
  }
  return valid;
}

// The largest half-height h such that every canvas pixel within (aspect * h, h) of `centre` (plus a
// pixel's margin) is valid; windows grow outwards, so the valid ones are those below a bound.
double LargestCentredWindow(const cv::Mat& valid, cv::Point2d centre, double aspect) {
  cv::Mat invalid = 1 - valid, sums;
  cv::integral(invalid, sums, CV_32S);
  const auto all_valid = [&](double h) {
    const int x0 = static_cast<int>(std::floor(centre.x - aspect * h)) - 1;
    const int x1 = static_cast<int>(std::ceil(centre.x + aspect * h)) + 1;
    const int y0 = static_cast<int>(std::floor(centre.y - h)) - 1;
    const int y1 = static_cast<int>(std::ceil(centre.y + h)) + 1;
    if (x0 < 0 || y0 < 0 || x1 >= valid.cols || y1 >= valid.rows) return false;
    return sums.at<int>(y1 + 1, x1 + 1) - sums.at<int>(y0, x1 + 1) - sums.at<int>(y1 + 1, x0) +
               sums.at<int>(y0, x0) ==
           0;
  };
  double lo = 0, hi = valid.rows;
  if (!all_valid(1)) return 0;
  for (int i = 0; i < 40; ++i) {
    const double mid = 0.5 * (lo + hi);
    (all_valid(mid) ? lo : hi) = mid;
  }
  return lo;
}

int EvenFloor(double value) { return 2 * static_cast<int>(std::floor(value / 2)); }

}  // namespace

StereoRectifier::StereoRectifier(const StereoCalibration& calibration, cv::Size output)
    : calibration_(calibration) {
  const cv::Size source = calibration.image_size;
  passthrough_ = calibration.kind == "rectified" && (output == cv::Size() || output == source);
  cv::Mat r[2], p[2], q;
  cv::stereoRectify(calibration.k1, calibration.d1, calibration.k2, calibration.d2, source, calibration.r,
                    calibration.t, r[0], r[1], p[0], p[1], q, cv::CALIB_ZERO_DISPARITY, 1, source);
  if (calibration.kind == "rectified") p[0] = cv::Mat(calibration.k1);
  const double canvas_focal = p[0].at<double>(0, 0);
  camera_.baseline = calibration.kind == "rectified" ? calibration.baseline()
                                                     : -p[1].at<double>(0, 3) / p[1].at<double>(0, 0);
  if (!(camera_.baseline > 0)) {
    // stereoRectify keeps the file's direction: a T whose x is positive puts the rectified right
    // eye on the left, every disparity turns negative and every depth with it (such a file prepared
    // a clip of 0% depth coverage without a word, and training then refused its negative depth
    // bounds; found 2026-12-06).
    const cv::Vec3d& t = calibration.t;
    if (std::abs(t[0]) < std::abs(t[1])) {
      FailInvalid(fmt::format(
          "{}: T = ({:.4g}, {:.4g}, {:.4g}) puts the eyes one above the other: depth is measured along "
          "rows, so the right eye must sit beside the left (T's x the largest part of T)",
          calibration.source, t[0], t[1], t[2]));
    }
    FailInvalid(fmt::format(
        "{}: T = ({:.4g}, {:.4g}, {:.4g}) puts the right eye to the left of the left eye (after "
        "rectification the baseline is {:.4g}): either the eyes are given the other way round (swap "
        "--left and --right, or the halves of the frame, and K1 D1 with K2 D2), or T's sign is flipped "
        "(X_right = R X_left + T, so a right eye on the right has T's x < 0, as OpenCV's stereoCalibrate "
        "writes it)",
        calibration.source, t[0], t[1], t[2], camera_.baseline));
  }
  camera_.left_rotation = cv::Matx33d(r[0]);
  camera_.right_rotation = cv::Matx33d(r[1]);
  if (passthrough_) {
    camera_.size = source;
    camera_.focal = calibration.k1(0, 0);
    camera_.left_rotation = camera_.right_rotation = cv::Matx33d::eye();
    camera_.baseline = calibration.baseline();
    return;
  }
  const double aspect = output == cv::Size() ? static_cast<double>(source.width) / source.height
                                             : static_cast<double>(output.width) / output.height;
  const cv::Point2d centre(p[0].at<double>(0, 2), p[0].at<double>(1, 2));
  double half_height = 0;
  if (calibration.kind == "rectified") {
    // Already rectified: the whole frame (cropped to the aspect) at the given focal length.
    half_height = std::min(source.height / 2.0, source.width / (2.0 * aspect));
    camera_.left_rotation = camera_.right_rotation = cv::Matx33d::eye();
    r[0] = cv::Mat::eye(3, 3, CV_64F);
    r[1] = cv::Mat::eye(3, 3, CV_64F);
  } else {
    half_height = LargestCentredWindow(ValidInBoth(calibration, r, p[0], source), centre, aspect);
  }
  if (half_height < 4) {
    FailInvalid(calibration.source +
                ": after rectification the two eyes share no usable window (is the "
                "calibration for this rig, and are left and right the right way round?)");
  }
  const double window_width = 2 * aspect * half_height, window_height = 2 * half_height;
  if (output == cv::Size()) {
    const double to_source = 0.5 * (calibration.k1(0, 0) + calibration.k2(0, 0)) / canvas_focal;
    output = {EvenFloor(window_width * to_source), EvenFloor(window_height * to_source)};
  }
  if (output.width < 2 || output.height < 2)
    FailInvalid(calibration.source + ": the rectified window is empty");
  // Both output sides fit inside the window (rounding never reaches outside it).
  const double scale = std::max(output.width / window_width, output.height / window_height);
  camera_.size = output;
  camera_.focal = canvas_focal * scale;
  camera_.scale = camera_.focal / (0.5 * (calibration.k1(0, 0) + calibration.k2(0, 0)));
  supersample_ = std::max(1, static_cast<int>(std::floor(1 / camera_.scale + 1e-9)));

  const int m = supersample_;
  const cv::Matx33d fine(camera_.focal * m, 0, (m * output.width - 1) / 2.0, 0, camera_.focal * m,
                         (m * output.height - 1) / 2.0, 0, 0, 1);
  const cv::Matx33d k[2] = {calibration.k1, calibration.k2};
  const cv::Mat d[2] = {calibration.d1, calibration.d2};
  for (int eye = 0; eye < 2; ++eye) {
    cv::initUndistortRectifyMap(k[eye], d[eye], r[eye], fine, output * m, CV_16SC2, map1_[eye], map2_[eye]);
  }
}

cv::Mat StereoRectifier::Apply(const cv::Mat& image, int eye) const {
  if (passthrough_) return image.clone();
  cv::Mat fine;
  cv::remap(image, fine, map1_[eye], map2_[eye], cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  if (supersample_ == 1) return fine;
  cv::Mat out;
  cv::resize(fine, out, camera_.size, 0, 0, cv::INTER_AREA);
  return out;
}

cv::Mat StereoRectifier::Binary(const cv::Mat& mask) {
  cv::Mat out;
  cv::threshold(mask, out, 127, 255, cv::THRESH_BINARY);
  return out;
}

std::vector<cv::Point2d> StereoRectifier::RectifyPoints(int eye, const std::vector<cv::Point2d>& raw) const {
  if (raw.empty()) return {};
  if (passthrough_) return raw;
  std::vector<cv::Point2d> out;
  const cv::Matx33d r = eye == 0 ? camera_.left_rotation : camera_.right_rotation;
  cv::undistortPoints(raw, out, eye == 0 ? calibration_.k1 : calibration_.k2,
                      eye == 0 ? calibration_.d1 : calibration_.d2, r, camera_.Matrix(),
                      cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-10));
  return out;
}

}  // namespace endorecon::prepare
