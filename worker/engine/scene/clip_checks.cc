#include "worker/engine/scene/clip_checks.h"

#include <Eigen/Dense>
#include <cmath>
#include <cstdio>

#include "common/error.h"

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
}

void CheckCamera(const Camera& camera, const std::string& where) {
  if (!std::isfinite(camera.fx) || !std::isfinite(camera.fy) || camera.fx <= 0 || camera.fy <= 0) {
    FailInvalid(where + ": focal length must be finite and positive (fx = " + Number(camera.fx) +
                ", fy = " + Number(camera.fy) + ")");
  }
  if (!std::isfinite(camera.cx) || !std::isfinite(camera.cy)) {
    FailInvalid(where + ": principal point is not finite (cx = " + Number(camera.cx) +
                ", cy = " + Number(camera.cy) + ")");
  }
  if (camera.width <= 0 || camera.height <= 0) {
    FailInvalid(where + ": image size must be positive (" + SizeText(camera.width, camera.height) + ")");
  }
  CheckPose(camera.c2w, where);
}

void CheckNearFar(double near, double far, const std::string& where) {
  if (!std::isfinite(near) || !std::isfinite(far) || near < 0 || near >= far) {
    FailInvalid(where + ": depth bounds must be finite with 0 <= near < far (near = " + Number(near) +
                ", far = " + Number(far) + ")");
  }
}

void CheckFrameLimit(int width, int height, std::size_t max_pixels, const std::string& where) {
  const auto pixels = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
  if (pixels > max_pixels) {
    Fail(ErrorCode::kResourceExhausted, where + ": frames of " + SizeText(width, height) + " (" +
                                            std::to_string(pixels) + " pixels) exceed the limit of " +
                                            std::to_string(max_pixels) + " pixels per frame");
  }
}

}  // namespace endorecon::scene
