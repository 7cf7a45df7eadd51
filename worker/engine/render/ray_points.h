// Turns one ray's samples into field inputs: normalised positions in the scene box, the unit view
// direction and time per sample, and intervals converted from z-depth to units of the box's
// longest side (densities are per box length, whatever the clip's units).
#pragma once

#include <Eigen/Core>
#include <cmath>

#include "common/hd.h"
#include "worker/engine/scene/scene_box.h"
#include "worker/engine/scene/view_geometry.h"

namespace endorecon::render {

// s[0..n): samples (z-depth) along origin + s * direction (direction with unit z-depth, see
// scene/view_geometry.h). Writes pos[3n], dir[3n], time[n]; rescales delta[0..n) in place.
ENDORECON_HD void RayPointsOf(const scene::BoxFrame& box, const double* origin, const double* direction,
                              float time, const float* s, int n, float* delta, float* pos, float* dir,
                              float* times) {
  const double length =
      std::sqrt(direction[0] * direction[0] + direction[1] * direction[1] + direction[2] * direction[2]);
  const double to_box = length / box.scale;
  double start[3], step[3];
  for (int c = 0; c < 3; ++c) {
    start[c] = (origin[c] - box.min[c]) * box.inv_size[c];
    step[c] = direction[c] * box.inv_size[c];
  }
  float unit[3];
  scene::UnitDirection(direction, unit);
  for (int j = 0; j < n; ++j) {
    for (int c = 0; c < 3; ++c) {
      pos[3 * j + c] = static_cast<float>(start[c] + double(s[j]) * step[c]);
      dir[3 * j + c] = unit[c];
    }
    times[j] = time;
    delta[j] = static_cast<float>(double(delta[j]) * to_box);
  }
}

inline void RayPoints(const scene::SceneBox& box, const Eigen::Vector3d& origin,
                      const Eigen::Vector3d& direction, float time, const float* s, int n, float* delta,
                      float* pos, float* dir, float* times) {
  RayPointsOf(box.Frame(), origin.data(), direction.data(), time, s, n, delta, pos, dir, times);
}

}  // namespace endorecon::render
