#include "worker/engine/eval/psnr.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "worker/engine/eval/image_size.h"

namespace endorecon::eval {

double Psnr(std::span<const float> rendered, std::span<const std::uint8_t> reference,
            std::span<const std::uint8_t> tool_mask, int width, int height) {
  CheckImageSize(rendered.size(), width, height, 3, "PSNR: rendered image");
  CheckImageSize(reference.size(), width, height, 3, "PSNR: reference image");
  CheckMaskSize(tool_mask.size(), width, height, "PSNR: tool mask");
  const std::size_t pixels = static_cast<std::size_t>(width) * height;
  double squared_error = 0;
  std::size_t kept = 0;
  for (std::size_t p = 0; p < pixels; ++p) {
    if (!tool_mask.empty() && tool_mask[p] != 0) continue;
    for (int c = 0; c < 3; ++c) {
      const double diff =
          std::clamp(static_cast<double>(rendered[3 * p + c]), 0.0, 1.0) - reference[3 * p + c] / 255.0;
      squared_error += diff * diff;
    }
    ++kept;
  }
  if (kept == 0) return std::numeric_limits<double>::quiet_NaN();
  return base::PsnrFromMse(squared_error / (3.0 * kept));
}

}  // namespace endorecon::eval
