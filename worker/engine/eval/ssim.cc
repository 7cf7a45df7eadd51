#include "worker/engine/eval/ssim.h"

#include <algorithm>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "worker/engine/eval/image_size.h"

namespace endorecon::eval {
namespace {

constexpr int kWindow = 11;
constexpr double kSigma = 1.5;
constexpr double kC1 = 0.01 * 0.01;
constexpr double kC2 = 0.03 * 0.03;

cv::Mat Blur(const cv::Mat& image) {
  cv::Mat out;
  cv::GaussianBlur(image, out, cv::Size(kWindow, kWindow), kSigma, kSigma, cv::BORDER_REFLECT);
  return out;
}

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
  // Double precision: sigma^2 = E[x^2] - mu^2 cancels badly in float on flat regions.
  cv::Mat x(height, width, CV_64FC3), y(height, width, CV_64FC3);
  for (int v = 0; v < height; ++v) {
    auto* xr = x.ptr<double>(v);
    auto* yr = y.ptr<double>(v);
    for (int u = 0; u < width; ++u) {
      const std::size_t p = static_cast<std::size_t>(v) * width + u;
      const bool tool = !tool_mask.empty() && tool_mask[p] != 0;
      for (int c = 0; c < 3; ++c) {
        xr[3 * u + c] = tool ? 0.0 : std::clamp(static_cast<double>(rendered[3 * p + c]), 0.0, 1.0);
        yr[3 * u + c] = tool ? 0.0 : reference[3 * p + c] / 255.0;
      }
    }
  }
  const cv::Mat mu_x = Blur(x), mu_y = Blur(y);
  const cv::Mat xx = Blur(x.mul(x)), yy = Blur(y.mul(y)), xy = Blur(x.mul(y));

  const int border = kWindow / 2;
  double sum = 0;
  std::size_t kept = 0;
  for (int v = border; v < height - border; ++v) {
    const auto* mx = mu_x.ptr<double>(v);
    const auto* my = mu_y.ptr<double>(v);
    const auto* sxx = xx.ptr<double>(v);
    const auto* syy = yy.ptr<double>(v);
    const auto* sxy = xy.ptr<double>(v);
    for (int u = border; u < width - border; ++u) {
      if (!tool_mask.empty() && tool_mask[static_cast<std::size_t>(v) * width + u] != 0) continue;
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
  return kept == 0 ? std::numeric_limits<double>::quiet_NaN() : sum / kept;
}

}  // namespace endorecon::eval
