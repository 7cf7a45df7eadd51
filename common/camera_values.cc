#include "common/camera_values.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

#include "common/error.h"

namespace endorecon {
namespace {

constexpr double kOrthonormalTolerance = 1e-3;

std::string Number(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.6g", value);
  return text;
}

}  // namespace

std::string SizeText(int width, int height) { return std::to_string(width) + "x" + std::to_string(height); }

void CheckRigidPose(const double* c2w, const std::string& where) {
  for (int i = 0; i < 12; ++i) {
    if (!std::isfinite(c2w[i])) FailInvalid(where + ": the pose has non-finite entries");
  }
  const auto r = [c2w](int row, int column) { return c2w[column * 3 + row]; };
  double error = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const double dot = r(0, i) * r(0, j) + r(1, i) * r(1, j) + r(2, i) * r(2, j);
      error = std::max(error, std::abs(dot - (i == j ? 1.0 : 0.0)));
    }
  }
  if (error > kOrthonormalTolerance) {
    FailInvalid(where + ": the pose's rotation is not orthonormal (max |RᵀR − I| = " + Number(error) + ")");
  }
  const double det = r(0, 0) * (r(1, 1) * r(2, 2) - r(1, 2) * r(2, 1)) -
                     r(0, 1) * (r(1, 0) * r(2, 2) - r(1, 2) * r(2, 0)) +
                     r(0, 2) * (r(1, 0) * r(2, 1) - r(1, 1) * r(2, 0));
  if (det < 0)
    FailInvalid(where + ": the pose's rotation has determinant " + Number(det) + " (a reflection)");
  // A centre past kMostDepth overflows the scene's single-precision arithmetic; it was reported
  // later as bounds the user never gave ("far = inf") or as cameras far apart, without a row.
  const double centre = std::hypot(c2w[9], c2w[10], c2w[11]);  // without overflow on its way
  if (centre > kMostDepth) {
    FailInvalid(where + ": the camera's centre lies " + Number(centre) + " from the origin, past " +
                Number(kMostDepth) + " (a translation in other units, or a broken value)");
  }
}

void CheckIntrinsics(double fx, double fy, double cx, double cy, int width, int height,
                     const std::string& where) {
  if (!std::isfinite(fx) || !std::isfinite(fy) || fx <= 0 || fy <= 0 || fx > kMostFocalPixels ||
      fy > kMostFocalPixels) {
    FailInvalid(where + ": focal length must be finite and positive (fx = " + Number(fx) +
                ", fy = " + Number(fy) + "), and at most " + Number(kMostFocalPixels) + " pixels");
  }
  if (width > 0 && height > 0) {
    const double degrees_per_radian = 180 / std::numbers::pi;
    const double across_x = 2 * std::atan(0.5 * width / fx) * degrees_per_radian;
    const double across_y = 2 * std::atan(0.5 * height / fy) * degrees_per_radian;
    if (std::max(across_x, across_y) > kMostFieldOfViewDegrees) {
      FailInvalid(where + ": the focal length (fx = " + Number(fx) + ", fy = " + Number(fy) +
                  ") gives a field of view of " + Number(across_x) + " x " + Number(across_y) +
                  " degrees across the " + SizeText(width, height) + " frame, more than " +
                  Number(kMostFieldOfViewDegrees) + " (a pinhole camera's; a focal length in other units?)");
    }
  }
  if (!std::isfinite(cx) || !std::isfinite(cy)) {
    FailInvalid(where + ": principal point is not finite (cx = " + Number(cx) + ", cy = " + Number(cy) + ")");
  }
  if (width <= 0 || height <= 0) {
    FailInvalid(where + ": image size must be positive (" + SizeText(width, height) + ")");
  }
  // The principal point lies in the frame (a crop may move it off the centre, not out of the image),
  // and the two focal lengths agree within kMostFocalAspect (square pixels give 1; anamorphic lenses
  // 1.33 to 2): cx = 5000 in a 96-pixel frame or fy = 1000 fx trained without a word (found 2026-12-05).
  if (cx < 0 || cx > width || cy < 0 || cy > height) {
    FailInvalid(where + ": the principal point (cx = " + Number(cx) + ", cy = " + Number(cy) +
                ") lies outside the " + SizeText(width, height) +
                " frame (a value in other units, or of another image size?)");
  }
  const double aspect = fy / fx;
  if (aspect > kMostFocalAspect || aspect < 1 / kMostFocalAspect) {
    FailInvalid(where + ": fy / fx is " + Number(aspect) + " (fx = " + Number(fx) + ", fy = " + Number(fy) +
                "); pixels are at most " + Number(kMostFocalAspect) +
                " times as tall as wide or wide as tall");
  }
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

}  // namespace endorecon
