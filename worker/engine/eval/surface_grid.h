// The 3D surface report.html draws for one frame: its rendered depth at every `stride`-th pixel, kept
// on the pixel grid so the page can join neighbours into triangles and back-project them through the
// frame's camera (as pointcloud/ is, eval::BackProject). Depth is quantised to 16 bits over the
// frame's range: a third of the bytes of quantised positions, for the same surface.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "worker/engine/scene/camera.h"

namespace endorecon::eval {

struct SurfaceGrid {
  static constexpr std::uint16_t kNoDepth = 65535;  // no surface at this grid point

  int width = 0, height = 0, stride = 1;    // grid points per row, rows; pixels between grid points
  double depth_origin = 0, depth_step = 0;  // z-depth = depth_origin + q * depth_step, clip units
  std::vector<std::uint16_t> depth;         // q per grid point, row-major, in [0, 65534] or kNoDepth
  std::vector<std::uint8_t> rgb;            // 3 per grid point
  std::vector<std::uint8_t> uncertainty;    // 1 per grid point: round(255 * u / bound), clamped
};

// The pixel column (or row) that grid column (or row) i samples: min(i * stride + stride / 2, size - 1).
inline int SurfacePixel(int i, int stride, int size) {
  return i * stride + stride / 2 < size ? i * stride + stride / 2 : size - 1;
}

// The smallest stride s >= 1 whose grid of ceil(width/s) x ceil(height/s) points has at most 65535
// points (WebGL 1 indexes vertices with 16 bits) and at most `budget` points over `frames` frames.
int SurfaceStride(int width, int height, int frames, std::size_t budget);

// A heat map's value at every grid point of a camera's image sampled with `stride` (as SampleSurface's
// points): round(255 * value / bound) clamped to [0, 255], a non-finite value 0; all 0 when `values` is
// empty. Throws InvalidArgument when values has neither 0 nor width x height entries, a stride < 1 or a
// bound that is not > 0.
std::vector<std::uint8_t> SampleHeat(const scene::Camera& camera, std::span<const float> values, double bound,
                                     int stride);

// Grid point (i, j) samples pixel (SurfacePixel(i), SurfacePixel(j)) of the camera's image. A point has
// no depth where the pixel is a tool pixel (tool_mask 1; an empty mask: none) or its depth is not
// finite and > 0. `rgb` is 8-bit RGB (W*H*3); `uncertainty` (W*H, or empty: all 0) is sampled by
// SampleHeat with `uncertainty_bound`. Throws InvalidArgument on sizes that disagree
// with the camera's or a stride < 1.
SurfaceGrid SampleSurface(const scene::Camera& camera, std::span<const float> depth,
                          std::span<const std::uint8_t> rgb, std::span<const float> uncertainty,
                          double uncertainty_bound, std::span<const std::uint8_t> tool_mask, int stride);

}  // namespace endorecon::eval
