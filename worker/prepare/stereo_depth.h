// Depth from a rectified stereo pair: OpenCV's semi-global matching (StereoSGBM, sub-pixel by its
// cost parabola) on both views, a left-right consistency check, optionally a Lucas-Kanade sub-pixel
// refinement of each disparity; depth = focal * baseline / disparity. (An edge-aware filter,
// ximgproc's weighted least squares, was measured and left out: docs/benchmarks.md.)
// Pixels without a trustworthy match (inconsistent, occluded, outside the right view, on a
// specular highlight in either eye, in an excluded region) get depth 0 = unknown.
#pragma once

#include <opencv2/core.hpp>
#include <string>

namespace endorecon::prepare {

struct DepthOptions {
  int block_size = 5;              // SGBM's matching window (odd)
  bool eight_paths = false;        // MODE_HH (8 paths, about twice the time) instead of MODE_SGBM_3WAY
  double max_lr_difference = 1;    // pixels between the left disparity and the right one it points to
  bool refine = false;             // Lucas-Kanade sub-pixel refinement of each disparity (9 x 9 window)
  int specular_min_channel = 200;  // SpecularMask's threshold; 256 disables the specular check

  std::string Describe() const;
};

// Disparities searched: [min, min + count), count a multiple of 16; smaller ones than `floor`
// (>= min) are not believed (depth unknown), so every depth found lies in
// [focal * baseline / max, focal * baseline / floor].
struct DisparityRange {
  int min = 0, count = 64;
  double floor = 0.5;
  int max() const { return min + count; }
};

struct StereoDepthResult {
  cv::Mat depth;      // CV_32F, calibration units, 0 = unknown
  cv::Mat disparity;  // CV_32F pixels, 0 where depth is unknown
};

// Thread-safe: each call builds its own matchers.
class StereoDepth {
 public:
  StereoDepth(const DepthOptions& options, DisparityRange range, double focal, double baseline);

  // `left`, `right`: rectified 8-bit BGR of one size; `excluded_left`, `excluded_right`: 0/255
  // masks of pixels to ignore (fixed screen regions), or empty.
  StereoDepthResult Compute(const cv::Mat& left, const cv::Mat& right, const cv::Mat& excluded_left = {},
                            const cv::Mat& excluded_right = {}) const;

 private:
  DepthOptions options_;
  DisparityRange range_;
  double focal_, baseline_;
};

}  // namespace endorecon::prepare
