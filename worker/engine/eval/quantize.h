// How a float colour in [0, 1] becomes the 8-bit value every export writes.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

namespace endorecon::eval {

// Clamped to [0, 1], scaled by 255 and rounded to nearest; NaN becomes 0.
inline std::uint8_t ToByte(float value) {
  if (std::isnan(value)) return 0;
  return static_cast<std::uint8_t>(std::lround(std::clamp(value, 0.0f, 1.0f) * 255.0f));
}

}  // namespace endorecon::eval
