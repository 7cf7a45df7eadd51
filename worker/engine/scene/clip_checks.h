// Checks shared by the clip loaders (the rules on plain numbers: common/camera_values.h). Each throws
// an endorecon::Error whose message starts with `where` (a file, or a file and a frame) and says what
// was found.
#pragma once

#include <Eigen/Core>
#include <cstddef>
#include <string>

#include "common/camera_values.h"
#include "worker/engine/scene/camera.h"

namespace endorecon::scene {

// The camera's intrinsics and pose, by common/camera_values.h's rules (CheckIntrinsics,
// CheckRigidPose).
void CheckCamera(const Camera& camera, const std::string& where);

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

}  // namespace endorecon::scene
