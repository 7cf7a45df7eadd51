#include "worker/engine/eval/pixel_error.h"

#include <algorithm>
#include <cmath>

#include "worker/engine/eval/image_size.h"

namespace endorecon::eval {

std::vector<float> PixelRmse(std::span<const float> rendered, std::span<const std::uint8_t> reference,
                             int width, int height) {
  CheckImageSize(rendered.size(), width, height, 3, "pixel error: rendered image");
  CheckImageSize(reference.size(), width, height, 3, "pixel error: reference image");
  std::vector<float> error(static_cast<std::size_t>(width) * height);
  for (std::size_t p = 0; p < error.size(); ++p) {
    double squares = 0;
    for (int c = 0; c < 3; ++c) {
      const double diff =
          std::clamp(static_cast<double>(rendered[3 * p + c]), 0.0, 1.0) - reference[3 * p + c] / 255.0;
      squares += diff * diff;
    }
    error[p] = static_cast<float>(std::sqrt(squares / 3.0));
  }
  return error;
}

}  // namespace endorecon::eval
