// A pinhole camera: camera-to-world pose in the OpenGL convention (x right, y up, looking down -z)
// and intrinsics in pixels. Rays through pixel centres have direction d with d·(-z_cam) = 1, so the
// distance parameter s along a ray is the z-depth along the optical axis, in the clip's units.
#pragma once

#include <Eigen/Core>

#include "worker/engine/scene/view_geometry.h"

namespace endorecon::scene {

struct Camera {
  Eigen::Matrix<double, 3, 4> c2w = Eigen::Matrix<double, 3, 4>::Identity();  // [R | t]
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;

  // Ray through the centre of pixel (u, v) (u right, v down), origin and unnormalised direction
  // with unit z-depth per unit s.
  void Ray(double u, double v, Eigen::Vector3d& origin, Eigen::Vector3d& direction) const {
    PixelRay(c2w.data(), fx, fy, cx, cy, u, v, origin.data(), direction.data());
  }

  // The inverse of Ray: where the world point `point` lands in the image, in pixel coordinates (pixel
  // (u, v) holds [u, u + 1) x [v, v + 1), its ray goes through the centre). False, with x and y left
  // as they were, for a point not in front of the camera (or NaN).
  bool ToPixel(const Eigen::Vector3d& point, double& x, double& y) const {
    const Eigen::Vector3d local = c2w.leftCols<3>().transpose() * (point - c2w.col(3));
    const double z = -local.z();  // looking down -z
    if (!(z > 0)) return false;
    x = fx * local.x() / z + cx;
    y = -fy * local.y() / z + cy;
    return true;
  }

  // Written out, not defaulted: CUDA sources include this header as C++17.
  bool operator==(const Camera& o) const {
    return c2w == o.c2w && fx == o.fx && fy == o.fy && cx == o.cx && cy == o.cy && width == o.width &&
           height == o.height;
  }
  bool operator!=(const Camera& o) const { return !(*this == o); }

  PinholeView View() const {
    PinholeView view;
    for (int i = 0; i < 12; ++i) view.c2w[i] = c2w.data()[i];
    view.fx = fx;
    view.fy = fy;
    view.cx = cx;
    view.cy = cy;
    view.width = width;
    view.height = height;
    return view;
  }
};

}  // namespace endorecon::scene
