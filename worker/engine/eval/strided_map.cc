#include "worker/engine/eval/strided_map.h"

#include <algorithm>

namespace endorecon::eval {

int GridSize(int extent, int stride) { return (extent - 1) / stride + 1; }

int StrideFor(int width, int height, int max_pixels, int min_stride) {
  int stride = std::max(1, min_stride);
  while (GridSize(width, stride) * GridSize(height, stride) > max_pixels) ++stride;
  return stride;
}

std::vector<int> StridedPixels(int width, int height, int stride) {
  std::vector<int> pixels;
  pixels.reserve(std::size_t(GridSize(width, stride)) * GridSize(height, stride));
  for (int y = 0; y < height; y += stride) {
    for (int x = 0; x < width; x += stride) pixels.push_back(y * width + x);
  }
  return pixels;
}

std::vector<float> UpsampleStrided(const std::vector<float>& grid, int width, int height, int stride) {
  const int gw = GridSize(width, stride), gh = GridSize(height, stride);
  std::vector<float> out(std::size_t(width) * height);
  const auto at = [&](int gx, int gy) { return grid[std::size_t(gy) * gw + gx]; };
  for (int y = 0; y < height; ++y) {
    const int gy0 = std::min(y / stride, gh - 1), gy1 = std::min(gy0 + 1, gh - 1);
    const float ty = gy1 == gy0 ? 0.0f : float(y - gy0 * stride) / float(stride);
    for (int x = 0; x < width; ++x) {
      const int gx0 = std::min(x / stride, gw - 1), gx1 = std::min(gx0 + 1, gw - 1);
      const float tx = gx1 == gx0 ? 0.0f : float(x - gx0 * stride) / float(stride);
      const float top = at(gx0, gy0) + tx * (at(gx1, gy0) - at(gx0, gy0));
      const float bottom = at(gx0, gy1) + tx * (at(gx1, gy1) - at(gx0, gy1));
      out[std::size_t(y) * width + x] = top + ty * (bottom - top);
    }
  }
  return out;
}

}  // namespace endorecon::eval
