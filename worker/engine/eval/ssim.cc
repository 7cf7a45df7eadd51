#include "worker/engine/eval/ssim.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <array>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "worker/engine/eval/image_size.h"

namespace endorecon::eval {
namespace {

constexpr int kWindow = kSsimLeastSide;
constexpr int kBorder = kWindow / 2;
constexpr double kSigma = 1.5;
constexpr double kC1 = 0.01 * 0.01;
constexpr double kC2 = 0.03 * 0.03;
// Window rows scored at a time. Every scored window lies wholly inside the frame, so a strip of
// rows needs only its own rows and kBorder on either side, and its scores equal the whole frame's.
// Whole-frame planes took 80 MB of fresh memory a call at 640 x 512 (ten planes of three doubles a
// pixel), and first touching those pages cost more than the arithmetic; strips of 16 rows keep the
// planes in the cache, allocated once a call and thread. Two SSIMs at 640 x 512 on the 2-core VM:
// 0.16-0.33 s whole-frame (0.03 s when the pages happened to be warm), 0.05 s in strips of 16
// (0.065 s on one thread; 0.07 s in strips of 32, 0.15 s of 128).
constexpr int kStripRows = 16;

// The five planes the score needs (x, y, x^2, y^2, xy; three channels each) for a strip of rows,
// and their blurs.
struct Planes {
  std::array<cv::Mat, 5> raw, blurred;
  Planes(int rows, int width) {
    for (cv::Mat& m : raw) m.create(rows, width, CV_64FC3);
    for (cv::Mat& m : blurred) m.create(rows, width, CV_64FC3);
  }
};

}  // namespace

double Ssim(std::span<const float> rendered, std::span<const std::uint8_t> reference,
            std::span<const std::uint8_t> tool_mask, int width, int height) {
  CheckImageSize(rendered.size(), width, height, 3, "SSIM: rendered image");
  CheckImageSize(reference.size(), width, height, 3, "SSIM: reference image");
  CheckMaskSize(tool_mask.size(), width, height, "SSIM: tool mask");
  if (width < kWindow || height < kWindow) {
    FailInvalid("SSIM: image " + std::to_string(width) + "x" + std::to_string(height) +
                " is smaller than the 11x11 window");
  }
  const auto tool = [&](int v, int u) {
    return !tool_mask.empty() && tool_mask[static_cast<std::size_t>(v) * width + u] != 0;
  };
  const int scored = height - 2 * kBorder, strips = (scored + kStripRows - 1) / kStripRows;
  tbb::enumerable_thread_specific<Planes> planes_of_thread(
      [&] { return Planes(std::min(kStripRows, scored) + 2 * kBorder, width); });
  // Per strip, summed in order below, so the score does not depend on how the strips were shared.
  std::vector<double> strip_sum(strips, 0.0);
  std::vector<std::size_t> strip_kept(strips, 0);
  tbb::parallel_for(0, strips, [&](int strip) {
    Planes& planes = planes_of_thread.local();
    const int first = kBorder + strip * kStripRows;
    const int last = std::min(first + kStripRows, height - kBorder);  // scored rows [first, last)
    const int top = first - kBorder, rows = last - first + 2 * kBorder;
    // Double precision: sigma^2 = E[x^2] - mu^2 cancels badly in float on flat regions.
    for (int i = 0; i < rows; ++i) {
      const int v = top + i;
      auto* x = planes.raw[0].ptr<double>(i);
      auto* y = planes.raw[1].ptr<double>(i);
      auto* xx = planes.raw[2].ptr<double>(i);
      auto* yy = planes.raw[3].ptr<double>(i);
      auto* xy = planes.raw[4].ptr<double>(i);
      for (int u = 0; u < width; ++u) {
        const std::size_t p = static_cast<std::size_t>(v) * width + u;
        const bool masked = tool(v, u);
        for (int k = 0; k < 3; ++k) {
          const int c = 3 * u + k;
          const double a = masked ? 0.0 : std::clamp(static_cast<double>(rendered[3 * p + k]), 0.0, 1.0);
          const double b = masked ? 0.0 : reference[3 * p + k] / 255.0;
          x[c] = a, y[c] = b, xx[c] = a * a, yy[c] = b * b, xy[c] = a * b;
        }
      }
    }
    for (std::size_t k = 0; k < planes.raw.size(); ++k) {
      cv::Mat out = planes.blurred[k].rowRange(0, rows);
      cv::GaussianBlur(planes.raw[k].rowRange(0, rows), out, cv::Size(kWindow, kWindow), kSigma, kSigma,
                       cv::BORDER_REFLECT | cv::BORDER_ISOLATED);
    }
    double sum = 0;
    std::size_t kept = 0;
    for (int v = first; v < last; ++v) {
      const int i = v - top;
      const auto* mx = planes.blurred[0].ptr<double>(i);
      const auto* my = planes.blurred[1].ptr<double>(i);
      const auto* sxx = planes.blurred[2].ptr<double>(i);
      const auto* syy = planes.blurred[3].ptr<double>(i);
      const auto* sxy = planes.blurred[4].ptr<double>(i);
      for (int u = kBorder; u < width - kBorder; ++u) {
        if (tool(v, u)) continue;
        double pixel = 0;
        for (int c = 3 * u; c < 3 * u + 3; ++c) {
          const double var_x = sxx[c] - mx[c] * mx[c];
          const double var_y = syy[c] - my[c] * my[c];
          const double cov = sxy[c] - mx[c] * my[c];
          pixel += (2 * mx[c] * my[c] + kC1) * (2 * cov + kC2) /
                   ((mx[c] * mx[c] + my[c] * my[c] + kC1) * (var_x + var_y + kC2));
        }
        sum += pixel / 3.0;
        ++kept;
      }
    }
    strip_sum[strip] = sum;
    strip_kept[strip] = kept;
  });
  double sum = 0;
  std::size_t kept = 0;
  for (int strip = 0; strip < strips; ++strip) sum += strip_sum[strip], kept += strip_kept[strip];
  return kept == 0 ? std::numeric_limits<double>::quiet_NaN() : sum / kept;
}

}  // namespace endorecon::eval
