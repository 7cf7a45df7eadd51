#include "worker/engine/eval/surface_grid.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "worker/engine/eval/image_size.h"

namespace endorecon::eval {

int SurfaceStride(int width, int height, int frames, std::size_t budget) {
  for (int s = 1;; ++s) {
    const std::size_t points = static_cast<std::size_t>((width + s - 1) / s) * ((height + s - 1) / s);
    if (points <= SurfaceGrid::kNoDepth && points * static_cast<std::size_t>(std::max(1, frames)) <= budget)
      return s;
    if (points == 1) return s;
  }
}

std::vector<std::uint8_t> SampleHeat(const scene::Camera& camera, std::span<const float> values, double bound,
                                     int stride) {
  const int w = camera.width, h = camera.height;
  CheckMaskSize(values.size(), w, h, "surface: heat map");
  if (stride < 1) FailInvalid("surface: stride " + std::to_string(stride) + " is below 1");
  if (!(bound > 0)) FailInvalid("surface: a heat map's bound must be > 0");
  const int gw = (w + stride - 1) / stride, gh = (h + stride - 1) / stride;
  std::vector<std::uint8_t> levels(static_cast<std::size_t>(gw) * gh, 0);
  if (values.empty()) return levels;
  for (int j = 0; j < gh; ++j) {
    for (int i = 0; i < gw; ++i) {
      const float value =
          values[static_cast<std::size_t>(SurfacePixel(j, stride, h)) * w + SurfacePixel(i, stride, w)];
      if (!std::isfinite(value)) continue;
      levels[static_cast<std::size_t>(j) * gw + i] =
          static_cast<std::uint8_t>(std::lround(255.0 * std::clamp(value / bound, 0.0, 1.0)));
    }
  }
  return levels;
}

SurfaceGrid SampleSurface(const scene::Camera& camera, std::span<const float> depth,
                          std::span<const std::uint8_t> rgb, std::span<const float> uncertainty,
                          double uncertainty_bound, std::span<const std::uint8_t> tool_mask, int stride) {
  const int w = camera.width, h = camera.height;
  CheckImageSize(depth.size(), w, h, 1, "surface: depth");
  CheckImageSize(rgb.size(), w, h, 3, "surface: colour");
  CheckMaskSize(tool_mask.size(), w, h, "surface: tool mask");
  SurfaceGrid grid;
  grid.uncertainty = SampleHeat(camera, uncertainty, uncertainty_bound, stride);
  grid.stride = stride;
  grid.width = (w + stride - 1) / stride;
  grid.height = (h + stride - 1) / stride;
  const std::size_t points = static_cast<std::size_t>(grid.width) * grid.height;
  std::vector<double> z(points, std::numeric_limits<double>::quiet_NaN());
  grid.rgb.assign(points * 3, 0);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (int j = 0; j < grid.height; ++j) {
    for (int i = 0; i < grid.width; ++i) {
      const int u = SurfacePixel(i, stride, w), v = SurfacePixel(j, stride, h);
      const std::size_t p = static_cast<std::size_t>(v) * w + u,
                        g = static_cast<std::size_t>(j) * grid.width + i;
      for (int c = 0; c < 3; ++c) grid.rgb[3 * g + c] = rgb[3 * p + c];
      if ((!tool_mask.empty() && tool_mask[p] != 0) || !std::isfinite(depth[p]) || depth[p] <= 0) continue;
      z[g] = depth[p];
      lo = std::min(lo, z[g]);
      hi = std::max(hi, z[g]);
    }
  }
  const double levels = SurfaceGrid::kNoDepth - 1;
  grid.depth_origin = std::isfinite(lo) ? lo : 0.0;
  grid.depth_step = std::isfinite(lo) ? (hi - lo) / levels : 0.0;
  grid.depth.assign(points, SurfaceGrid::kNoDepth);
  for (std::size_t g = 0; g < points; ++g) {
    if (std::isnan(z[g])) continue;
    const double q = grid.depth_step > 0 ? (z[g] - grid.depth_origin) / grid.depth_step : 0.0;
    grid.depth[g] = static_cast<std::uint16_t>(std::lround(std::clamp(q, 0.0, levels)));
  }
  return grid;
}

}  // namespace endorecon::eval
