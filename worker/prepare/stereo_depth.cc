#include "worker/prepare/stereo_depth.h"

#include <tbb/parallel_for.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/error.h"
#include "worker/prepare/specular_mask.h"

namespace endorecon::prepare {
namespace {

constexpr int kSubpixel = 16;     // SGBM's disparities are in 1/16 pixel
constexpr int kRefineRadius = 4;  // the refinement's window: 9 x 9 (larger: less noise, slower)

cv::Ptr<cv::StereoSGBM> MakeMatcher(const DepthOptions& options, DisparityRange range, cv::Size size) {
  const int b = options.block_size;
  const double area = static_cast<double>(size.area()) / (640.0 * 512.0);
  const int speckle_window = std::max(20, static_cast<int>(100 * area));
  return cv::StereoSGBM::create(
      range.min, range.count, b, 8 * 3 * b * b, 32 * 3 * b * b, -1, 63, 10, speckle_window, 2,
      options.eight_paths ? cv::StereoSGBM::MODE_HH : cv::StereoSGBM::MODE_SGBM_3WAY);
}

// Left disparities (pixels, CV_32F, NaN where SGBM found none or the right view disagrees by more
// than `max_difference`).
// `left16`, `right16` are of images padded by `pad` columns on each side; the result is not.
cv::Mat ConsistentDisparity(const cv::Mat& left16, const cv::Mat& right16, DisparityRange range,
                            double max_difference, int pad) {
  const int width = left16.cols - 2 * pad;
  cv::Mat out(left16.rows, width, CV_32F, cv::Scalar(NAN));
  for (int y = 0; y < left16.rows; ++y) {
    const short* l = left16.ptr<short>(y) + pad;
    const short* r = right16.ptr<short>(y) + pad;
    float* o = out.ptr<float>(y);
    for (int x = 0; x < width; ++x) {
      const double d = static_cast<double>(l[x]) / kSubpixel;
      if (d < range.min || d >= range.max()) continue;
      const int xr = static_cast<int>(std::lround(x - d));
      if (xr < 0 || xr >= width) continue;  // outside the right view: occluded by its frame
      const double dr = static_cast<double>(r[xr]) / kSubpixel;
      if (dr < range.min || dr >= range.max() || std::abs(dr - d) > max_difference) continue;
      o[x] = static_cast<float>(d);
    }
  }
  return out;
}

// Lucas-Kanade along the epipolar line: Gauss-Newton steps of each disparity that align a window
// of the left view (mean-free intensities) with the right view sampled at that one disparity,
// from the matcher's estimate. It removes the matcher's pull towards whole pixels (SGBM's cost
// parabola); steps that would move more than half a pixel from the matcher's value are refused.
void RefineSubpixel(const cv::Mat& left_bgr, const cv::Mat& right_bgr, int radius, cv::Mat& disparity) {
  cv::Mat left, right, right_dx;
  cv::cvtColor(left_bgr, left, cv::COLOR_BGR2GRAY);
  cv::cvtColor(right_bgr, right, cv::COLOR_BGR2GRAY);
  left.convertTo(left, CV_32F);
  right.convertTo(right, CV_32F);
  cv::Sobel(right, right_dx, CV_32F, 1, 0, 3, 1.0 / 8);
  const int w = left.cols, h = left.rows, n = (2 * radius + 1) * (2 * radius + 1);
  tbb::parallel_for(radius, h - radius, [&](int y) {
    float* d = disparity.ptr<float>(y);
    std::vector<float> l(static_cast<std::size_t>(n)), r(l.size()), g(l.size());
    for (int x = radius; x < w - radius; ++x) {
      if (std::isnan(d[x])) continue;
      const float start = d[x];
      float current = start;
      for (int iteration = 0; iteration < 3; ++iteration) {
        const float xr = static_cast<float>(x) - current;
        const int x0 = static_cast<int>(std::floor(xr)) - radius;
        if (x0 < 0 || x0 + 2 * radius + 1 >= w) break;
        const float a = xr - std::floor(xr);
        float lm = 0, rm = 0, gm = 0;
        int k = 0;
        for (int j = -radius; j <= radius; ++j) {
          const float* lrow = left.ptr<float>(y + j) + x - radius;
          const float* rrow = right.ptr<float>(y + j) + x0;
          const float* grad_row = right_dx.ptr<float>(y + j) + x0;
          for (int i = 0; i <= 2 * radius; ++i, ++k) {
            l[k] = lrow[i];
            r[k] = rrow[i] + a * (rrow[i + 1] - rrow[i]);
            g[k] = grad_row[i] + a * (grad_row[i + 1] - grad_row[i]);
            lm += l[k];
            rm += r[k];
            gm += g[k];
          }
        }
        lm /= n;
        rm /= n;
        gm /= n;
        float ge = 0, gg = 0;
        for (k = 0; k < n; ++k) {
          const float gk = g[k] - gm;
          ge += gk * ((l[k] - lm) - (r[k] - rm));
          gg += gk * gk;
        }
        if (gg < 1e-3f) break;
        // d enters as R(x - d): the step -sum(g e) / sum(g g) lowers the residual.
        const float next = current - ge / gg;
        if (std::abs(next - start) > 0.5f) break;
        current = next;
      }
      d[x] = current;
    }
  });
}

// Unknown where `mask` (0/255, in the right view) covers the pixel the disparity points to.
void DropWhereRightMasked(const cv::Mat& mask, cv::Mat& disparity) {
  if (mask.empty()) return;
  for (int y = 0; y < disparity.rows; ++y) {
    float* d = disparity.ptr<float>(y);
    const std::uint8_t* m = mask.ptr<std::uint8_t>(y);
    for (int x = 0; x < disparity.cols; ++x) {
      if (std::isnan(d[x])) continue;
      const int xr = static_cast<int>(std::lround(x - d[x]));
      if (xr < 0 || xr >= disparity.cols || m[xr]) d[x] = NAN;
    }
  }
}

}  // namespace

std::string DepthOptions::Describe() const {
  return std::string("SGBM ") + (eight_paths ? "8-path (MODE_HH)" : "3-way (MODE_SGBM_3WAY)") + ", block " +
         std::to_string(block_size) + ", left-right check " + std::to_string(max_lr_difference) + " px" +
         (refine ? ", sub-pixel refinement" : "");
}

StereoDepth::StereoDepth(const DepthOptions& options, DisparityRange range, double focal, double baseline)
    : options_(options), range_(range), focal_(focal), baseline_(baseline) {
  if (options.block_size < 1 || options.block_size % 2 == 0 || options.block_size > 31) {
    FailInvalid("depth block size must be odd, from 1 to 31, found " + std::to_string(options.block_size));
  }
  if (range.min < 0 || range.count < 16 || range.count % 16 != 0 || !(range.floor > 0)) {
    FailInvalid("disparity range [" + std::to_string(range.min) + ", " + std::to_string(range.max()) +
                ") must start at >= 0 and span a positive multiple of 16");
  }
}

StereoDepthResult StereoDepth::Compute(const cv::Mat& left, const cv::Mat& right,
                                       const cv::Mat& excluded_left, const cv::Mat& excluded_right) const {
  const cv::Ptr<cv::StereoSGBM> matcher = MakeMatcher(options_, range_, left.size());
  // SGBM leaves the first min + count columns of the left view (and the last of the right view)
  // unmatched; padding both sides lets every real pixel search its whole range.
  const int pad = range_.max();
  cv::Mat left_padded, right_padded, left16, right16;
  cv::copyMakeBorder(left, left_padded, 0, 0, pad, pad, cv::BORDER_CONSTANT);
  cv::copyMakeBorder(right, right_padded, 0, 0, pad, pad, cv::BORDER_CONSTANT);
  matcher->compute(left_padded, right_padded, left16);
  // The right view's disparities: the same matcher on the mirrored pair (the right eye mirrored is
  // a left eye). Written here rather than taken from ximgproc's createRightMatcher, which would
  // bring all of libopencv-contrib for four lines.
  cv::Mat left_mirrored, right_mirrored;
  cv::flip(right_padded, left_mirrored, 1);
  cv::flip(left_padded, right_mirrored, 1);
  matcher->compute(left_mirrored, right_mirrored, right16);
  cv::flip(right16, right16, 1);
  cv::Mat disparity = ConsistentDisparity(left16, right16, range_, options_.max_lr_difference, pad);

  if (options_.refine) RefineSubpixel(left, right, kRefineRadius, disparity);

  cv::Mat unknown_left = excluded_left.empty() ? cv::Mat::zeros(left.size(), CV_8U) : excluded_left.clone();
  cv::Mat unknown_right =
      excluded_right.empty() ? cv::Mat::zeros(left.size(), CV_8U) : excluded_right.clone();
  if (options_.specular_min_channel <= 255) {
    const int grow = std::max(2, left.cols / 160);  // the highlight's halo misleads matching too
    unknown_left |= SpecularMask(left, options_.specular_min_channel, grow);
    unknown_right |= SpecularMask(right, options_.specular_min_channel, grow);
  }
  disparity.setTo(NAN, unknown_left);
  DropWhereRightMasked(unknown_right, disparity);

  StereoDepthResult result{cv::Mat(left.size(), CV_32F, cv::Scalar(0)),
                           cv::Mat(left.size(), CV_32F, cv::Scalar(0))};
  const double fb = focal_ * baseline_;
  for (int y = 0; y < disparity.rows; ++y) {
    const float* d = disparity.ptr<float>(y);
    float* z = result.depth.ptr<float>(y);
    float* o = result.disparity.ptr<float>(y);
    for (int x = 0; x < disparity.cols; ++x) {
      if (std::isnan(d[x]) || d[x] < range_.floor) continue;
      o[x] = d[x];
      z[x] = static_cast<float>(fb / d[x]);
    }
  }
  return result;
}

}  // namespace endorecon::prepare
