#include "worker/engine/scene/scene_box.h"

#include <algorithm>
#include <limits>

namespace endorecon::scene {

SceneBox FrustumBox(const std::vector<Camera>& cameras, double near, double far, double padding) {
  SceneBox box;
  box.min.setConstant(std::numeric_limits<double>::infinity());
  box.max.setConstant(-std::numeric_limits<double>::infinity());
  for (const auto& camera : cameras) {
    const double us[2] = {-0.5, camera.width - 0.5};
    const double vs[2] = {-0.5, camera.height - 0.5};
    for (double u : us) {
      for (double v : vs) {
        Eigen::Vector3d origin, direction;
        camera.Ray(u, v, origin, direction);
        for (double s : {near, far}) {
          const Eigen::Vector3d x = origin + s * direction;
          box.min = box.min.cwiseMin(x);
          box.max = box.max.cwiseMax(x);
        }
      }
    }
  }
  // Keep every side at least a small fraction of the longest so no axis is degenerate.
  const double longest = (box.max - box.min).maxCoeff();
  for (int k = 0; k < 3; ++k) {
    const double side = box.max[k] - box.min[k];
    const double pad = padding * longest + 0.5 * std::max(0.0, 0.05 * longest - side);
    box.min[k] -= pad;
    box.max[k] += pad;
  }
  return box;
}

SceneBox ObjectBox(double radius, double padding) {
  SceneBox box;
  const double half = radius * (1.0 + 2.0 * padding);
  box.min.setConstant(-half);
  box.max.setConstant(half);
  return box;
}

SceneBox ClipBox(const Clip& clip) {
  return clip.object_radius > 0 ? ObjectBox(clip.object_radius) : FrustumBox(clip.cameras, clip.near, clip.far);
}

double TypicalDepth(const Clip& clip) {
  std::vector<float> values;
  for (const auto& frame : clip.depth) {
    for (std::size_t i = 0; i < frame.size(); i += 97) {
      if (frame[i] > 0) values.push_back(frame[i]);
    }
  }
  if (values.empty()) return 0.5 * (clip.near + clip.far);
  std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
  return values[values.size() / 2];
}

}  // namespace endorecon::scene
