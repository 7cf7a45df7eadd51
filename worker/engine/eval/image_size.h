// The size contract every metric and export checks: an image is a row-major span of
// width * height * channels values; a tool mask is empty (no mask) or width * height values.
#pragma once

#include <cstddef>
#include <string>

#include "common/error.h"

namespace endorecon::eval {

// Throws InvalidArgument naming `what` when `size` is not width * height * channels.
inline void CheckImageSize(std::size_t size, int width, int height, int channels, const std::string& what) {
  if (width <= 0 || height <= 0) {
    FailInvalid(what + ": image size " + std::to_string(width) + "x" + std::to_string(height) +
                " is not positive");
  }
  const std::size_t expected = static_cast<std::size_t>(width) * height * channels;
  if (size != expected) {
    FailInvalid(what + ": has " + std::to_string(size) + " values, expected " + std::to_string(expected) +
                " (" + std::to_string(width) + "x" + std::to_string(height) + "x" + std::to_string(channels) +
                ")");
  }
}

// As CheckImageSize for one channel, but an empty mask (the clip has none) is accepted.
inline void CheckMaskSize(std::size_t size, int width, int height, const std::string& what) {
  if (size != 0) CheckImageSize(size, width, height, 1, what);
}

}  // namespace endorecon::eval
