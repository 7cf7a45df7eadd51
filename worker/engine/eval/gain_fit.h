// A held-out frame's exposure is not predictable from its neighbours when the camera's exposure
// flickers; evaluation can fit it, as NeRF-W fits a test image's appearance: one gain per colour
// channel, in closed form over the tissue, applied to the render before it is scored. Three numbers
// against thousands of pixels: the score still measures shape, texture and motion.
#pragma once

#include <array>
#include <cstdint>
#include <span>
#include <vector>

namespace endorecon::eval {

struct GainFit {
  std::array<double, 3> gain{1, 1, 1};  // per channel: sum r*o / sum r^2 over the unmasked pixels
  std::vector<float> rgb;               // the render times the gains, clamped to [0, 1]
};

// `rendered` float RGB, `reference` uint8 RGB (/255), `mask` empty or 1 = left out. A channel with
// no signal keeps gain 1. Throws InvalidArgument on bad sizes.
GainFit FitGain(std::span<const float> rendered, std::span<const std::uint8_t> reference,
                std::span<const std::uint8_t> mask, int width, int height);

}  // namespace endorecon::eval
