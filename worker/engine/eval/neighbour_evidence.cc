#include "worker/engine/eval/neighbour_evidence.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <string>

#include "common/error.h"
#include "worker/engine/eval/model_uncertainty.h"

namespace endorecon::eval {

std::vector<float> ResidualEvidence(std::span<const float> rgb, std::span<const std::uint8_t> image,
                                    std::span<const std::uint8_t> tool_mask) {
  const std::size_t n = rgb.size() / 3;
  if (rgb.size() != 3 * n || image.size() != rgb.size() || (!tool_mask.empty() && tool_mask.size() != n)) {
    FailInvalid("ResidualEvidence: " + std::to_string(rgb.size()) + " colour values, " +
                std::to_string(image.size()) + " image values and " + std::to_string(tool_mask.size()) +
                " mask values do not describe one set of pixels");
  }
  std::vector<float> residual(rgb.size());
  for (std::size_t i = 0; i < rgb.size(); ++i) {
    residual[i] = !tool_mask.empty() && tool_mask[i / 3] != 0
                      ? std::numeric_limits<float>::quiet_NaN()
                      : std::clamp(rgb[i], 0.0f, 1.0f) - float(image[i]) / 255.0f;
  }
  return residual;
}

std::vector<float> NeighbourEvidence(std::span<const scene::Camera> cameras, int f,
                                     std::span<const float> rgb, std::span<const float> depth,
                                     std::span<const std::uint8_t> tool_mask,
                                     const std::vector<std::vector<float>>& evidence) {
  const int count = int(cameras.size());
  if (f < 0 || f >= count || evidence.size() != cameras.size()) {
    FailInvalid("NeighbourEvidence: frame " + std::to_string(f) + " of " + std::to_string(count) +
                " cameras with evidence for " + std::to_string(evidence.size()) + " frames");
  }
  const scene::Camera& camera = cameras[f];
  const int w = camera.width, h = camera.height;
  const std::size_t n = std::size_t(w) * h;
  if (depth.size() != n || rgb.size() != 3 * n || (!tool_mask.empty() && tool_mask.size() != n)) {
    FailInvalid("NeighbourEvidence: frame " + std::to_string(f) + " is " + std::to_string(w) + " x " +
                std::to_string(h) + " but its depth has " + std::to_string(depth.size()) +
                " values, its colours " + std::to_string(rgb.size()) + " and its mask " +
                std::to_string(tool_mask.size()));
  }
  std::vector<double> sum(3 * n, 0.0), weights(n, 0.0);
  // The surface point f sees at each pixel, computed once for every moving neighbour (NaN: no depth).
  std::vector<Eigen::Vector3d> surface;
  const auto surface_points = [&]() -> const std::vector<Eigen::Vector3d>& {
    if (!surface.empty()) return surface;
    surface.assign(n, Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN()));
    Eigen::Vector3d origin, direction;
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const std::size_t p = std::size_t(v) * w + u;
        if (!(std::isfinite(depth[p]) && depth[p] > 0)) continue;
        camera.Ray(u, v, origin, direction);
        surface[p] = origin + double(depth[p]) * direction;
      }
    }
    return surface;
  };
  for (int g = std::max(0, f - kNeighbourFrames); g <= std::min(count - 1, f + kNeighbourFrames); ++g) {
    if (g == f || evidence[g].empty()) continue;
    const scene::Camera& other = cameras[g];
    if (evidence[g].size() != 3 * std::size_t(other.width) * other.height) {
      FailInvalid("NeighbourEvidence: frame " + std::to_string(g) + "'s evidence has " +
                  std::to_string(evidence[g].size()) + " values for a " + std::to_string(other.width) +
                  " x " + std::to_string(other.height) + " camera");
    }
    const double weight = 1.0 / std::abs(g - f);
    // A still camera (an EndoNeRF clip's) sees a surface point at the same pixel in every frame.
    const std::vector<Eigen::Vector3d>* points = other == camera ? nullptr : &surface_points();
    for (int v = 0; v < h; ++v) {
      for (int u = 0; u < w; ++u) {
        const std::size_t p = std::size_t(v) * w + u;
        int gu = u, gv = v;
        if (points != nullptr && !std::isnan((*points)[p].x())) {
          double x = 0, y = 0;
          if (!other.ToPixel((*points)[p], x, y)) continue;                          // behind g's camera
          if (!(x >= 0 && y >= 0 && x < other.width && y < other.height)) continue;  // NaN too
          gu = int(x);  // the pixel whose square holds it
          gv = int(y);
        }
        if (gu >= other.width || gv >= other.height)
          continue;  // no depth: the same pixel, in a smaller image
        const float* residual = &evidence[g][3 * (std::size_t(gv) * other.width + gu)];
        if (std::isnan(residual[0])) continue;  // g's tool
        for (int c = 0; c < 3; ++c) sum[3 * p + c] += weight * residual[c];
        weights[p] += weight;
      }
    }
  }
  std::vector<float> squared(n, 0.0f);
  for (std::size_t p = 0; p < n; ++p) {
    if (!(weights[p] > 0)) continue;
    double length = 0;
    for (int c = 0; c < 3; ++c) length += (sum[3 * p + c] / weights[p]) * (sum[3 * p + c] / weights[p]);
    squared[p] = static_cast<float>(length);
  }
  return RelativeToBrightnessMedian(rgb, squared, tool_mask);
}

}  // namespace endorecon::eval
