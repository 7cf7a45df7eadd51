#include "worker/engine/scene/clip_checks.h"

#include <spdlog/spdlog.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

#include "common/error.h"
#include "worker/engine/scene/clip.h"

namespace endorecon::scene {
namespace {

constexpr double kOrthonormalTolerance = 1e-3;

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.6g", value);
  return text;
}

}  // namespace

std::string SizeText(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

void CheckPose(const Eigen::Matrix<double, 3, 4>& c2w, const std::string& where) {
  if (!c2w.allFinite()) FailInvalid(where + ": the pose has non-finite entries");
  const Eigen::Matrix3d r = c2w.leftCols<3>();
  const double error = (r.transpose() * r - Eigen::Matrix3d::Identity()).cwiseAbs().maxCoeff();
  if (error > kOrthonormalTolerance) {
    FailInvalid(where + ": the pose's rotation is not orthonormal (max |RᵀR − I| = " + Number(error) + ")");
  }
  const double det = r.determinant();
  if (det < 0)
    FailInvalid(where + ": the pose's rotation has determinant " + Number(det) + " (a reflection)");
  // A centre past kMostDepth overflows the scene's single-precision arithmetic; it was reported
  // later as bounds the user never gave ("far = inf") or as cameras far apart, without a row.
  const double centre = c2w.col(3).stableNorm();  // without overflow on its way
  if (centre > kMostDepth) {
    FailInvalid(where + ": the camera's centre lies " + Number(centre) + " from the origin, past " +
                Number(kMostDepth) + " (a translation in other units, or a broken value)");
  }
}

void CheckCamera(const Camera& camera, const std::string& where) {
  if (!std::isfinite(camera.fx) || !std::isfinite(camera.fy) || camera.fx <= 0 || camera.fy <= 0 ||
      camera.fx > kMostFocalPixels || camera.fy > kMostFocalPixels) {
    FailInvalid(where + ": focal length must be finite and positive (fx = " + Number(camera.fx) +
                ", fy = " + Number(camera.fy) + "), and at most " + Number(kMostFocalPixels) + " pixels");
  }
  if (camera.width > 0 && camera.height > 0) {
    const double degrees_per_radian = 180 / std::numbers::pi;
    const double across_x = 2 * std::atan(0.5 * camera.width / camera.fx) * degrees_per_radian;
    const double across_y = 2 * std::atan(0.5 * camera.height / camera.fy) * degrees_per_radian;
    if (std::max(across_x, across_y) > kMostFieldOfViewDegrees) {
      FailInvalid(where + ": the focal length (fx = " + Number(camera.fx) + ", fy = " + Number(camera.fy) +
                  ") gives a field of view of " + Number(across_x) + " x " + Number(across_y) +
                  " degrees across the " + SizeText(camera.width, camera.height) + " frame, more than " +
                  Number(kMostFieldOfViewDegrees) + " (a pinhole camera's; a focal length in other units?)");
    }
  }
  if (!std::isfinite(camera.cx) || !std::isfinite(camera.cy)) {
    FailInvalid(where + ": principal point is not finite (cx = " + Number(camera.cx) +
                ", cy = " + Number(camera.cy) + ")");
  }
  if (camera.width <= 0 || camera.height <= 0) {
    FailInvalid(where + ": image size must be positive (" + SizeText(camera.width, camera.height) + ")");
  }
  // The principal point lies in the frame (a crop may move it off the centre, not out of the image),
  // and the two focal lengths agree within kMostFocalAspect (square pixels give 1; anamorphic lenses
  // 1.33 to 2): cx = 5000 in a 96-pixel frame or fy = 1000 fx trained without a word (found 2026-12-05).
  if (camera.cx < 0 || camera.cx > camera.width || camera.cy < 0 || camera.cy > camera.height) {
    FailInvalid(where + ": the principal point (cx = " + Number(camera.cx) + ", cy = " + Number(camera.cy) +
                ") lies outside the " + SizeText(camera.width, camera.height) +
                " frame (a value in other units, or of another image size?)");
  }
  const double aspect = camera.fy / camera.fx;
  if (aspect > kMostFocalAspect || aspect < 1 / kMostFocalAspect) {
    FailInvalid(where + ": fy / fx is " + Number(aspect) + " (fx = " + Number(camera.fx) +
                ", fy = " + Number(camera.fy) + "); pixels are at most " + Number(kMostFocalAspect) +
                " times as tall as wide or wide as tall");
  }
  CheckPose(camera.c2w, where);
}

void CheckNearFar(double near, double far, const std::string& where) {
  if (!std::isfinite(near) || !std::isfinite(far) || near < 0 || near >= far) {
    FailInvalid(where + ": depth bounds must be finite with 0 <= near < far (near = " + Number(near) +
                ", far = " + Number(far) + ")");
  }
  if (far > kMostDepth) {
    FailInvalid(where + ": the far bound " + Number(far) + " is beyond " + Number(kMostDepth) +
                ": the depth bounds are in implausible units");
  }
  if (far - near < kLeastDepthRange * far) {
    FailInvalid(where + ": the depth range is too thin to sample (near = " + Number(near) +
                ", far = " + Number(far) + ": far - near under " + Number(kLeastDepthRange) + " of far)");
  }
}

void CheckClipGeometry(const Clip& clip, const std::string& where) {
  double spread = 0;
  for (const Camera& a : clip.cameras) {
    for (const Camera& b : clip.cameras) {
      spread = std::max(spread, (a.c2w.col(3) - b.c2w.col(3)).stableNorm());
      if (spread > kMostCameraSpread * clip.far) {
        FailInvalid(where + ": the cameras' centres lie " + Number(spread) + " apart, more than " +
                    Number(kMostCameraSpread) + " times the far bound (" + Number(clip.far) +
                    "): a pose's translation is likely in other units than the depth bounds");
      }
    }
  }
  // The results (point clouds, meshes) hold single-precision coordinates, in the clip's frame: far
  // from its origin they step by more than a thousandth of the depth range (poses translated by 1e9
  // came back as points on a grid of 64 units; found 2026-12-05).
  double farthest = 0;
  for (const Camera& camera : clip.cameras) farthest = std::max(farthest, camera.c2w.col(3).stableNorm());
  const double step = farthest * std::numeric_limits<float>::epsilon();
  if (step > 1e-3 * (clip.far - clip.near)) {
    spdlog::warn(
        "{}: the cameras lie up to {} from the origin, where the results' single-precision coordinates "
        "step by about {}, more than a thousandth of the depth range ({} to {}): move the poses' origin "
        "into the scene for exact point clouds and meshes",
        where, Number(farthest), Number(step), Number(clip.near), Number(clip.far));
  }
  std::size_t outside = 0, seen = 0;
  for (const auto& frame : clip.depth) {
    for (std::size_t i = 0; i < frame.size(); i += 61) {
      if (!(frame[i] > 0)) continue;
      ++seen;
      outside += InOtherUnits(frame[i], clip.near, clip.far);
    }
  }
  if (seen > 0 && 2 * outside > seen) {
    spdlog::warn(
        "{}: {:.0f}% of the depth priors lie outside [near / 2, 2 far] = [{}, {}]: are the depth "
        "maps in the poses' units? The depth loss and depth-guided sampling follow them as they are",
        where, 100.0 * double(outside) / double(seen), Number(0.5 * clip.near), Number(2 * clip.far));
  }
}

void CheckFrameLimit(int width, int height, std::size_t max_pixels, const std::string& where) {
  const auto pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (pixels > max_pixels) {
    // The input's fault, not a resource another worker has: INVALID_ARGUMENT, so the job fails at once
    // (as RESOURCE_EXHAUSTED it was retried on three leases and read as vanished workers).
    Fail(ErrorCode::kInvalidArgument, where + ": frames of " + SizeText(width, height) + " (" +
                                          std::to_string(pixels) + " pixels) exceed the limit of " +
                                          std::to_string(max_pixels) + " pixels per frame");
  }
}

}  // namespace endorecon::scene
