#include "worker/engine/render/ray_points.h"

namespace endorecon::render {

void RayPoints(const scene::SceneBox& box, const Eigen::Vector3d& origin, const Eigen::Vector3d& direction,
               float time, const float* s, int n, float* delta, float* pos, float* dir, float* times) {
  const double length = direction.norm();
  const Eigen::Vector3d unit = direction / length;
  const double to_box = length / box.scale();
  const Eigen::Vector3d inv_size = (box.max - box.min).cwiseInverse();
  const Eigen::Vector3d start = (origin - box.min).cwiseProduct(inv_size);
  const Eigen::Vector3d step = direction.cwiseProduct(inv_size);
  for (int j = 0; j < n; ++j) {
    const Eigen::Vector3d p = start + double(s[j]) * step;
    for (int c = 0; c < 3; ++c) {
      pos[3 * j + c] = float(p[c]);
      dir[3 * j + c] = float(unit[c]);
    }
    times[j] = time;
    delta[j] = float(double(delta[j]) * to_box);
  }
}

}  // namespace endorecon::render
