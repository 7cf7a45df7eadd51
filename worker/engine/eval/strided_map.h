// A per-pixel map rendered only at every s-th pixel of every s-th row (the reduced frames'
// uncertainty, eval_plan.h) and brought back to every pixel.
#pragma once

#include <cstddef>
#include <span>
#include <vector>

namespace endorecon::eval {

// Row-major indices of the pixels (x, y) with x % stride == 0 and y % stride == 0, row by row: a grid
// of GridSize(width, stride) x GridSize(height, stride).
std::vector<int> StridedPixels(int width, int height, int stride);
int GridSize(int extent, int stride);

// The smallest stride >= min_stride whose grid holds at most max_pixels pixels.
int StrideFor(int width, int height, int max_pixels, int min_stride = 1);

// The values of `image` (row-major, `channels` per pixel) at `pixels`, in their order; an empty image
// (a frame without a mask) gives an empty result.
template <typename T>
std::vector<T> Gather(std::span<const T> image, const std::vector<int>& pixels, int channels = 1) {
  if (image.empty()) return {};
  std::vector<T> out(pixels.size() * std::size_t(channels));
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    for (int c = 0; c < channels; ++c) out[i * channels + c] = image[std::size_t(pixels[i]) * channels + c];
  }
  return out;
}

// Bilinear interpolation of a grid map (values at the StridedPixels positions) to width x height;
// pixels past the last grid row or column take its value. Written here rather than with cv::resize,
// whose area-aligned sample positions are not the grid's pixel positions.
std::vector<float> UpsampleStrided(const std::vector<float>& grid, int width, int height, int stride);

}  // namespace endorecon::eval
