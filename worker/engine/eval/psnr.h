// Peak signal-to-noise ratio between a rendered frame and its reference.
#pragma once

#include <cstdint>
#include <span>

#include "worker/engine/base/psnr_from_mse.h"

namespace endorecon::eval {

using base::kPsnrCapDb;

// PSNR in dB, peak 1, between `rendered` (float RGB, width*height*3, clamped to [0, 1] first as the
// PNG a user sees) and `reference` (uint8 RGB, 255 = 1.0). The MSE runs over every channel of the
// pixels whose `tool_mask` value is 0 (1 = tool, left out); an empty mask keeps every pixel.
// Returns NaN when no pixel is left (an all-tool frame), at most kPsnrCapDb otherwise.
// Throws InvalidArgument when a size disagrees with width x height.
double Psnr(std::span<const float> rendered, std::span<const std::uint8_t> reference,
            std::span<const std::uint8_t> tool_mask, int width, int height);

}  // namespace endorecon::eval
