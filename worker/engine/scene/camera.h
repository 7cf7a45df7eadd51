// A pinhole camera: camera-to-world pose in the OpenGL convention (x right, y up, looking down -z)
// and intrinsics in pixels. Rays through pixel centres have direction d with d·(-z_cam) = 1, so the
// distance parameter s along a ray is the z-depth along the optical axis, in the clip's units.
#pragma once

#include <Eigen/Core>

namespace endorecon::scene {

struct Camera {
  Eigen::Matrix<double, 3, 4> c2w = Eigen::Matrix<double, 3, 4>::Identity();  // [R | t]
  double fx = 0, fy = 0, cx = 0, cy = 0;
  int width = 0, height = 0;

  // Ray through the centre of pixel (u, v) (u right, v down), origin and unnormalised direction
  // with unit z-depth per unit s.
  void Ray(double u, double v, Eigen::Vector3d& origin, Eigen::Vector3d& direction) const {
    const Eigen::Vector3d d_cam((u + 0.5 - cx) / fx, -(v + 0.5 - cy) / fy, -1.0);
    direction = c2w.leftCols<3>() * d_cam;
    origin = c2w.col(3);
  }
};

}  // namespace endorecon::scene
