// The geometry per-ray code needs, as plain numbers and ENDORECON_HD functions, so the CPU loops and
// the CUDA kernels compute the same rays: a pinhole camera's ray through a pixel, and the scene box's
// normalisation into the field's unit cube. scene::Camera and scene::SceneBox hand out these views.
#pragma once

#include <cmath>

#include "common/hd.h"

namespace endorecon::scene {

// A scene::Camera as plain numbers.
struct PinholeView {
  double c2w[12] = {};  // 3 x 4 camera-to-world [R | t], column-major (Eigen's order)
  double fx = 1, fy = 1, cx = 0, cy = 0;
  int width = 0, height = 0;
};

// The ray through the centre of pixel (u, v) (u right, v down) in the OpenGL convention (x right,
// y up, looking down -z): origin and unnormalised direction with unit z-depth per unit of s.
ENDORECON_HD void PixelRay(const double* c2w, double fx, double fy, double cx, double cy, double u, double v,
                           double* origin, double* direction) {
  const double d[3] = {(u + 0.5 - cx) / fx, -(v + 0.5 - cy) / fy, -1.0};
  for (int r = 0; r < 3; ++r) {
    direction[r] = c2w[r] * d[0] + c2w[3 + r] * d[1] + c2w[6 + r] * d[2];
    origin[r] = c2w[9 + r];
  }
}

ENDORECON_HD void PixelRay(const PinholeView& view, int pixel, double* origin, double* direction) {
  PixelRay(view.c2w, view.fx, view.fy, view.cx, view.cy, pixel % view.width, pixel / view.width, origin,
           direction);
}

// A ray's direction scaled to unit length (the field's view direction, the learned background's
// input), rounded to S once.
template <typename S>
ENDORECON_HD void UnitDirection(const double* direction, S* unit) {
  const double length =
      std::sqrt(direction[0] * direction[0] + direction[1] * direction[1] + direction[2] * direction[2]);
  for (int c = 0; c < 3; ++c) unit[c] = static_cast<S>(direction[c] / length);
}

// The scene box as the field sees it: p_unit = (p - min) * inv_size; distances in box units are
// distances divided by `scale` (the box's longest side).
struct BoxFrame {
  double min[3] = {0, 0, 0};
  double inv_size[3] = {1, 1, 1};
  double scale = 1;
};

}  // namespace endorecon::scene
