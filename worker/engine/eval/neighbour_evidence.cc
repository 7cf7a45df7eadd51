#include "worker/engine/eval/neighbour_evidence.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
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

namespace {

// The walk both terms share: for each frame g != f within `reach` of f that is_neighbour(g), and each
// pixel p of f, visit(g, weight, p, q) with weight 1 / |g - f| and q the pixel of g's image where the
// surface f sees at p (f's rendered depth) projects; p itself where g's camera is f's (a still camera) or
// the depth is not finite and positive. Pixels whose surface falls behind or outside g's camera are
// skipped. f's sizes are the caller's to check.
template <typename IsNeighbour, typename Visit>
void ForEachNeighbourPixel(std::span<const scene::Camera> cameras, int f, std::span<const float> depth,
                           int reach, IsNeighbour is_neighbour, Visit visit) {
  const int count = int(cameras.size());
  const scene::Camera& camera = cameras[f];
  const int w = camera.width, h = camera.height;
  const std::size_t n = std::size_t(w) * h;
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
  for (int g = std::max(0, f - reach); g <= std::min(count - 1, f + reach); ++g) {
    if (g == f || !is_neighbour(g)) continue;
    const scene::Camera& other = cameras[g];
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
        visit(g, weight, p, std::size_t(gv) * other.width + gu);
      }
    }
  }
}

// Per pixel the squared length of the weighted mean (sum: 3 values a pixel, weights one); 0 where the
// weight is (next to) none.
std::vector<float> SquaredMean(std::span<const double> sum, std::span<const double> weights) {
  constexpr double kNoWeight = 1e-6;  // a blurred weight this small holds no neighbour's pixel
  std::vector<float> squared(weights.size(), 0.0f);
  for (std::size_t p = 0; p < weights.size(); ++p) {
    if (!(weights[p] > kNoWeight)) continue;
    double length = 0;
    for (int c = 0; c < 3; ++c) length += (sum[3 * p + c] / weights[p]) * (sum[3 * p + c] / weights[p]);
    squared[p] = static_cast<float>(length);
  }
  return squared;
}

// Throws InvalidArgument unless f is one of the cameras and its colours, depth and mask fit its camera.
void CheckFrame(const char* what, std::span<const scene::Camera> cameras, int f, std::span<const float> rgb,
                std::span<const float> depth, std::span<const std::uint8_t> tool_mask) {
  if (f < 0 || f >= int(cameras.size())) {
    FailInvalid(std::string(what) + ": frame " + std::to_string(f) + " of " + std::to_string(cameras.size()) +
                " cameras");
  }
  const scene::Camera& camera = cameras[f];
  const std::size_t n = std::size_t(camera.width) * camera.height;
  if (depth.size() != n || rgb.size() != 3 * n || (!tool_mask.empty() && tool_mask.size() != n)) {
    FailInvalid(std::string(what) + ": frame " + std::to_string(f) + " is " + std::to_string(camera.width) +
                " x " + std::to_string(camera.height) + " but its depth has " + std::to_string(depth.size()) +
                " values, its colours " + std::to_string(rgb.size()) + " and its mask " +
                std::to_string(tool_mask.size()));
  }
}

}  // namespace

std::vector<float> NeighbourEvidence(std::span<const scene::Camera> cameras, int f,
                                     std::span<const float> rgb, std::span<const float> depth,
                                     std::span<const std::uint8_t> tool_mask,
                                     const std::vector<std::vector<float>>& evidence) {
  if (evidence.size() != cameras.size()) {
    FailInvalid("NeighbourEvidence: " + std::to_string(cameras.size()) + " cameras with evidence for " +
                std::to_string(evidence.size()) + " frames");
  }
  CheckFrame("NeighbourEvidence", cameras, f, rgb, depth, tool_mask);
  const std::size_t n = depth.size();
  std::vector<double> sum(3 * n, 0.0), weights(n, 0.0);
  const auto has_evidence = [&](int g) {
    if (evidence[g].empty()) return false;
    const scene::Camera& other = cameras[g];
    if (evidence[g].size() != 3 * std::size_t(other.width) * other.height) {
      FailInvalid("NeighbourEvidence: frame " + std::to_string(g) + "'s evidence has " +
                  std::to_string(evidence[g].size()) + " values for a " + std::to_string(other.width) +
                  " x " + std::to_string(other.height) + " camera");
    }
    return true;
  };
  ForEachNeighbourPixel(cameras, f, depth, kNeighbourFrames, has_evidence,
                        [&](int g, double weight, std::size_t p, std::size_t q) {
                          const float* residual = &evidence[g][3 * q];
                          if (std::isnan(residual[0])) return;  // g's tool
                          for (int c = 0; c < 3; ++c) sum[3 * p + c] += weight * residual[c];
                          weights[p] += weight;
                        });
  return RelativeToBrightnessMedian(rgb, SquaredMean(sum, weights), tool_mask);
}

std::vector<float> NeighbourDisagreement(std::span<const scene::Camera> cameras, int f,
                                         std::span<const float> rgb, std::span<const float> depth,
                                         std::span<const NeighbourImage> images) {
  if (images.size() != cameras.size()) {
    FailInvalid("NeighbourDisagreement: " + std::to_string(cameras.size()) + " cameras with images for " +
                std::to_string(images.size()) + " frames");
  }
  CheckFrame("NeighbourDisagreement", cameras, f, rgb, depth, {});
  const scene::Camera& camera = cameras[f];
  const std::size_t n = depth.size();
  const auto is_training = [&](int g) {
    const NeighbourImage& image = images[g];
    if (image.rgb.empty()) return false;
    const std::size_t pixels = std::size_t(cameras[g].width) * cameras[g].height;
    if (image.rgb.size() != 3 * pixels || (!image.tool_mask.empty() && image.tool_mask.size() != pixels)) {
      FailInvalid("NeighbourDisagreement: frame " + std::to_string(g) + "'s image has " +
                  std::to_string(image.rgb.size()) + " values and its mask " +
                  std::to_string(image.tool_mask.size()) + " for a " + std::to_string(cameras[g].width) +
                  " x " + std::to_string(cameras[g].height) + " camera");
    }
    return true;
  };
  // The weighted sums and their weights as images, blurred alike below.
  cv::Mat sum(camera.height, camera.width, CV_64FC3, cv::Scalar::all(0)),
      weights(camera.height, camera.width, CV_64F, cv::Scalar::all(0));
  auto* sums = sum.ptr<double>();
  auto* weight_of = weights.ptr<double>();
  ForEachNeighbourPixel(
      cameras, f, depth, kDisagreementFrames, is_training,
      [&](int g, double weight, std::size_t p, std::size_t q) {
        const NeighbourImage& image = images[g];
        if (!image.tool_mask.empty() && image.tool_mask[q] != 0) return;  // g's tool
        for (int c = 0; c < 3; ++c) {
          sums[3 * p + c] += weight * (std::clamp(rgb[3 * p + c], 0.0f, 1.0f) - image.rgb[3 * q + c] / 255.0);
        }
        weight_of[p] += weight;
      });
  // Blurring the sums and the weights alike averages over the neighbourhood without pulling pixels no
  // neighbour sees towards 0 (a normalised convolution).
  cv::GaussianBlur(sum, sum, cv::Size(0, 0), kDisagreementBlurPixels, kDisagreementBlurPixels,
                   cv::BORDER_REFLECT);
  cv::GaussianBlur(weights, weights, cv::Size(0, 0), kDisagreementBlurPixels, kDisagreementBlurPixels,
                   cv::BORDER_REFLECT);
  return SquaredMean({sums, 3 * n}, {weight_of, n});
}

}  // namespace endorecon::eval
