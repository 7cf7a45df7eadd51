// Turns one ray's samples into field inputs: normalised positions in the scene box, the unit view
// direction and time per sample, and intervals converted from z-depth to units of the box's
// longest side (densities are per box length, whatever the clip's units).
#pragma once

#include <Eigen/Core>

#include "worker/engine/scene/scene_box.h"

namespace endorecon::render {

// s[0..n): samples (z-depth) along origin + s * direction (direction with unit z-depth, see
// scene/camera.h). Writes pos[3n], dir[3n], time[n]; rescales delta[0..n) in place.
void RayPoints(const scene::SceneBox& box, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
               float time, const float* s, int n, float* delta, float* pos, float* dir, float* times);

}  // namespace endorecon::render
