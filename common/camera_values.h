// The values a clip's cameras and depth bounds must hold, checked on plain numbers: one set of rules
// for the worker's loaders (worker/engine/scene/clip_checks.h) and for the CLI, which checks a clip's
// poses before its upload (client/clip_check.h). Each check throws Error(kInvalidArgument) whose
// message starts with `where` (a file, or a file and a row or frame) and says what was found.
#pragma once

#include <string>

namespace endorecon {

// Intrinsics: 0 < fx, fy ≤ kMostFocalPixels (a 1e300 focal length trained without a word), a field
// of view across the frame of at most kMostFieldOfViewDegrees on either axis (a pinhole camera's; a
// camera_angle_x of pi gave fx = 1e-14 and trained without a word), fy / fx within
// [1 / kMostFocalAspect, kMostFocalAspect], the principal point (cx, cy) inside the frame
// ([0, width] x [0, height]), width and height > 0.
constexpr double kMostFocalPixels = 1e9;
constexpr double kMostFieldOfViewDegrees = 170;
constexpr double kMostFocalAspect = 4;
void CheckIntrinsics(double fx, double fy, double cx, double cy, int width, int height,
                     const std::string& where);

// A camera-to-world [R | t] (`c2w`: 3 x 4, column by column, as Eigen stores it): every entry
// finite, R orthonormal (max |RᵀR − I| ≤ 1e-3) with det +1, and the centre t within kMostDepth of
// the origin.
void CheckRigidPose(const double* c2w, const std::string& where);

// Depth bounds: finite, 0 ≤ near < far ≤ kMostDepth, and far − near at least kLeastDepthRange of
// far (a thinner range leaves the samplers nothing to place samples in; a farther bound overflows the
// scene box's arithmetic in single precision).
constexpr double kLeastDepthRange = 1e-4;
constexpr double kMostDepth = 1e12;
void CheckNearFar(double near, double far, const std::string& where);

// "WxH", for messages.
std::string SizeText(int width, int height);

}  // namespace endorecon
