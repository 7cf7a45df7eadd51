// Structural similarity (Wang et al. 2004) between a rendered frame and its reference.
#pragma once

#include <cstdint>
#include <span>

namespace endorecon::eval {

// Mean SSIM, with the standard constants: an 11x11 Gaussian window of sigma 1.5, K1 = 0.01,
// K2 = 0.03, dynamic range 1, computed per channel and averaged over R, G, B. Inputs as Psnr:
// `rendered` float RGB clamped to [0, 1], `reference` uint8 RGB, `tool_mask` empty or 1 = tool.
// As the reference implementation, only windows that lie wholly inside the frame count (a border
// of 5 pixels is left out), so both sides must be at least 11 pixels.
// With a mask, tool pixels are set to 0 in both images first (so the tool's own content does not
// spill into neighbouring tissue windows, as EndoNeRF's evaluation), and the SSIM map is averaged
// over tissue pixels only. Returns NaN when no pixel is left. Throws InvalidArgument on bad sizes.
double Ssim(std::span<const float> rendered, std::span<const std::uint8_t> reference,
            std::span<const std::uint8_t> tool_mask, int width, int height);

// The smallest width and height Ssim takes (its window's).
inline constexpr int kSsimLeastSide = 11;

}  // namespace endorecon::eval
