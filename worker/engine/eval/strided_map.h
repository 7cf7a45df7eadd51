// A per-pixel map rendered only at every s-th pixel of every s-th row (the reduced frames'
// uncertainty, eval_plan.h) and brought back to every pixel.
#pragma once

#include <vector>

namespace endorecon::eval {

// Row-major indices of the pixels (x, y) with x % stride == 0 and y % stride == 0, row by row: a grid
// of GridSize(width, stride) x GridSize(height, stride).
std::vector<int> StridedPixels(int width, int height, int stride);
int GridSize(int extent, int stride);

// Bilinear interpolation of a grid map (values at the StridedPixels positions) to width x height;
// pixels past the last grid row or column take its value. Written here rather than with cv::resize,
// whose area-aligned sample positions are not the grid's pixel positions.
std::vector<float> UpsampleStrided(const std::vector<float>& grid, int width, int height, int stride);

}  // namespace endorecon::eval
