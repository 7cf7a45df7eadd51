#include "worker/engine/eval/gain_fit.h"

#include <algorithm>

#include "worker/engine/eval/image_size.h"

namespace endorecon::eval {

GainFit FitGain(std::span<const float> rendered, std::span<const std::uint8_t> reference,
                std::span<const std::uint8_t> mask, int width, int height) {
  CheckImageSize(rendered.size(), width, height, 3, "gain fit: rendered image");
  CheckImageSize(reference.size(), width, height, 3, "gain fit: reference image");
  CheckMaskSize(mask.size(), width, height, "gain fit: mask");
  const std::size_t pixels = std::size_t(width) * height;
  double cross[3] = {}, square[3] = {};
  for (std::size_t p = 0; p < pixels; ++p) {
    if (!mask.empty() && mask[p]) continue;
    for (int c = 0; c < 3; ++c) {
      const double r = std::clamp(double(rendered[3 * p + c]), 0.0, 1.0);
      cross[c] += r * (reference[3 * p + c] / 255.0);
      square[c] += r * r;
    }
  }
  GainFit fit;
  for (int c = 0; c < 3; ++c) {
    if (square[c] > 0) fit.gain[c] = cross[c] / square[c];
  }
  fit.rgb.resize(rendered.size());
  for (std::size_t i = 0; i < rendered.size(); ++i) {
    fit.rgb[i] = float(std::clamp(std::clamp(double(rendered[i]), 0.0, 1.0) * fit.gain[i % 3], 0.0, 1.0));
  }
  return fit;
}

}  // namespace endorecon::eval
