#include "worker/engine/eval/one_colour.h"

#include <array>
#include <cmath>
#include <limits>

#include "worker/engine/base/psnr_from_mse.h"

namespace endorecon::eval {

double OneColourPsnr(std::span<const std::uint8_t> image) {
  const std::size_t pixels = image.size() / 3;
  if (pixels == 0) return std::numeric_limits<double>::quiet_NaN();
  std::array<double, 3> sum{}, squares{};
  for (std::size_t i = 0; i < pixels * 3; ++i) {
    const double v = image[i] / 255.0;
    sum[i % 3] += v;
    squares[i % 3] += v * v;
  }
  double mse = 0;  // each channel's variance about its mean, averaged over the channels
  for (int c = 0; c < 3; ++c) {
    const double mean = sum[c] / double(pixels);
    mse += std::max(0.0, squares[c] / double(pixels) - mean * mean) / 3;
  }
  return base::PsnrFromMse(mse);
}

double MeanOneColourPsnr(const scene::Clip& clip, const std::vector<int>& frames) {
  if (frames.empty()) return std::numeric_limits<double>::quiet_NaN();
  double total = 0;
  for (const int f : frames) total += OneColourPsnr(clip.rgb.at(static_cast<std::size_t>(f)));
  return total / double(frames.size());
}

}  // namespace endorecon::eval
