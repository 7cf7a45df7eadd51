// The axis-aligned box the field lives in: every camera frustum between the clip's near and far,
// padded, or for a camera rig centred on an object the cube around the object (ClipBox). Field
// coordinates are positions mapped into [0,1]^3 by this box; rays are sampled only inside it
// (render/camera_ray.h); distances along rays are measured in units of the box's longest side so
// densities do not depend on the clip's units.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "worker/engine/scene/camera.h"
#include "worker/engine/scene/clip.h"
#include "worker/engine/scene/view_geometry.h"

namespace endorecon::scene {

struct SceneBox {
  Eigen::Vector3d min = Eigen::Vector3d::Zero();
  Eigen::Vector3d max = Eigen::Vector3d::Ones();

  double scale() const { return (max - min).maxCoeff(); }
  Eigen::Vector3d Normalise(const Eigen::Vector3d& x) const { return (x - min).cwiseQuotient(max - min); }
  BoxFrame Frame() const {
    BoxFrame frame;
    for (int k = 0; k < 3; ++k) {
      frame.min[k] = min[k];
      frame.inv_size[k] = 1.0 / (max[k] - min[k]);
    }
    frame.scale = scale();
    return frame;
  }
};

// The box around all cameras' frusta between near and far, padded by `padding` of its size per side.
SceneBox FrustumBox(const std::vector<Camera>& cameras, double near, double far, double padding = 0.05);

// The cube around the sphere of `radius` about the origin, padded by `padding` of its side per side.
SceneBox ObjectBox(double radius, double padding = 0.05);

// A clip's box: ObjectBox of a centred rig's object_radius, otherwise FrustumBox of its cameras
// (a frustum box around cameras that circle an object would spend most of the field on empty space
// outside the object).
SceneBox ClipBox(const Clip& clip);

// How far from the camera a clip's surface typically lies (z-depth, clip units): the median of its
// depth priors (a sparse subsample), or the middle of [near, far] for a clip without depth.
double TypicalDepth(const Clip& clip);

}  // namespace endorecon::scene
