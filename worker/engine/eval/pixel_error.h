// The per-pixel error the uncertainty is judged against and error/NNNNNN.png shows.
#pragma once

#include <cstdint>
#include <span>
#include <vector>

namespace endorecon::eval {

// Per pixel, the RMSE over the three channels: sqrt(mean_c (rendered_c - reference_c)^2), with
// `rendered` float RGB clamped to [0, 1] and `reference` uint8 RGB scaled by 1/255 (as Psnr).
// Returns width*height values in [0, 1]. Throws InvalidArgument on bad sizes.
std::vector<float> PixelRmse(std::span<const float> rendered, std::span<const std::uint8_t> reference,
                             int width, int height);

}  // namespace endorecon::eval
