// Checks shared by the clip loaders. Each throws an endorecon::Error whose message starts with
// `where` (a file, or a file and a frame) and says what was found.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <string>

#include "worker/engine/scene/camera.h"

namespace endorecon::scene {

// A camera-to-world [R | t]: every entry finite, R orthonormal (max |RᵀR − I| ≤ 1e-3) with det +1,
// and the centre t within kMostDepth of the origin.
void CheckPose(const Eigen::Matrix<double, 3, 4>& c2w, const std::string& where);

// Intrinsics: 0 < fx, fy ≤ kMostFocalPixels (a 1e300 focal length trained without a word), a field
// of view across the frame of at most kMostFieldOfViewDegrees on either axis (a pinhole camera's; a
// camera_angle_x of pi gave fx = 1e-14 and trained without a word), fy / fx within
// [1 / kMostFocalAspect, kMostFocalAspect], the principal point (cx, cy) inside the frame
// ([0, width] x [0, height]), width and height > 0; and the pose (CheckPose).
constexpr double kMostFocalPixels = 1e9;
constexpr double kMostFieldOfViewDegrees = 170;
constexpr double kMostFocalAspect = 4;
void CheckCamera(const Camera& camera, const std::string& where);

// Depth bounds: finite, 0 ≤ near < far ≤ kMostDepth, and far − near at least kLeastDepthRange of
// far (a thinner range leaves the samplers nothing to place samples in; a farther bound overflows the
// scene box's arithmetic in single precision).
constexpr double kLeastDepthRange = 1e-4;
constexpr double kMostDepth = 1e12;
void CheckNearFar(double near, double far, const std::string& where);

// What the clip's files say together, checked once they are loaded (`where`: the clip's folder):
// the cameras' centres lie within kMostCameraSpread times `far` of each other (farther, a pose's
// translation is in other units, and the scene box would hold nothing a ray samples), else
// Error(kInvalidArgument); and depth priors mostly outside [near / 2, 2 far] are warned of (depth in
// other units than the poses), naming the share.
constexpr double kMostCameraSpread = 1e4;
struct Clip;
void CheckClipGeometry(const Clip& clip, const std::string& where);

// Whether a depth prior lies so far outside [near, far] (below near / 2, above 2 far) that the depth
// maps are likely in other units than the poses; CheckClipGeometry warns when most do, and
// FitBoundsToPriors (depth_bounds.h) then leaves the bounds alone.
inline bool InOtherUnits(float prior, double near, double far) {
  return prior < 0.5 * near || prior > 2 * far;
}

// width x height must not exceed max_pixels; otherwise Error(kInvalidArgument).
void CheckFrameLimit(int width, int height, std::size_t max_pixels, const std::string& where);

// "WxH", for messages.
std::string SizeText(int width, int height);

}  // namespace endorecon::scene
