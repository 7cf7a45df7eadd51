// The one way a pixel becomes samples for the field, shared by training, depth refinement and
// rendering, on the CPU and in CUDA kernels: the camera ray of the pixel, the part of [near, far]
// worth sampling (its occupied span when an occupancy grid is given), a sampler that places depths
// and intervals there, and RayPointsOf, which turns them into field inputs.
#pragma once

#include <cstdint>

#include "common/hd.h"
#include "worker/engine/render/occupancy_grid.h"
#include "worker/engine/render/ray_points.h"
#include "worker/engine/scene/camera.h"
#include "worker/engine/scene/scene_box.h"
#include "worker/engine/scene/view_geometry.h"

namespace endorecon::render {

// A pixel's ray (origin, direction with unit z-depth) and its span [lo, hi].
struct CameraRay {
  double origin[3] = {0, 0, 0}, direction[3] = {0, 0, 1};
  float lo = 0, hi = 1;
};

// The occupancy cells a ray consults: res^3 cells (occupancy_grid.h), none when cells is null.
struct OccupancyView {
  const std::uint8_t* cells = nullptr;
  int res = 0;
};

// The part [*lo, *hi] of [near, far] where origin + s * direction lies in the box (slab test); a ray
// that misses the box gets the empty span [near, near]: nothing is sampled and it sees the background.
// Every ray of a frustum box stays inside it between near and far, so only object boxes cut rays.
ENDORECON_HD void BoxSpan(const scene::BoxFrame& box, const double* origin, const double* direction,
                          double near, double far, double* lo, double* hi) {
  double enter = near, leave = far;
  for (int c = 0; c < 3; ++c) {
    const double low = box.min[c], high = box.min[c] + 1.0 / box.inv_size[c];
    if (direction[c] == 0) {
      if (origin[c] < low || origin[c] > high) leave = enter - 1;  // parallel to the slab, outside it
      continue;
    }
    double t0 = (low - origin[c]) / direction[c], t1 = (high - origin[c]) / direction[c];
    if (t0 > t1) {
      const double t = t0;
      t0 = t1;
      t1 = t;
    }
    enter = t0 > enter ? t0 : enter;
    leave = t1 < leave ? t1 : leave;
  }
  if (!(enter < leave)) enter = leave = near;
  *lo = enter;
  *hi = leave;
}

// The ray of `pixel` (row-major index) of `view`; its span is the part of [near, far] in the box, or
// the occupied span of that part when the occupancy view has cells.
ENDORECON_HD CameraRay CameraRayOfPixel(const scene::PinholeView& view, int pixel, const scene::BoxFrame& box,
                                        const OccupancyView& occupancy, double near, double far) {
  CameraRay ray;
  scene::PixelRay(view, pixel, ray.origin, ray.direction);
  BoxSpan(box, ray.origin, ray.direction, near, far, &near, &far);
  double lo = near, hi = far;
  if (occupancy.cells != nullptr)
    RaySpan(occupancy.cells, occupancy.res, box, ray.origin, ray.direction, near, far, &lo, &hi);
  ray.lo = static_cast<float>(lo);
  ray.hi = static_cast<float>(hi);
  return ray;
}

// The same for a scene::Camera and an OccupancyGrid (null or empty: no skipping).
CameraRay CameraRayOf(const scene::Camera& camera, int pixel, const scene::SceneBox& box,
                      const OccupancyGrid* occupancy, double near, double far);

// Where a ray's samples go: depths s and intervals delta (n each), field inputs pos, dir (3n) and time (n).
struct RaySlot {
  float* s = nullptr;
  float* delta = nullptr;
  float* pos = nullptr;
  float* dir = nullptr;
  float* time = nullptr;
};

// Ray r of arrays laid out ray-major with n samples per ray.
ENDORECON_HD RaySlot RaySlotOf(float* s, float* delta, float* pos, float* dir, float* time, int r, int n) {
  const std::size_t o = static_cast<std::size_t>(r) * n;
  return {s + o, delta + o, pos + 3 * o, dir + 3 * o, time + o};
}

// sample(lo, hi, s, delta) places the ray's n samples within its span; RayPointsOf then makes them
// field inputs at `time` (intervals rescaled to box units).
template <typename Sample>
ENDORECON_HD void PlaceSamples(const CameraRay& ray, const scene::BoxFrame& box, float time, int n,
                               const Sample& sample, const RaySlot& slot) {
  sample(ray.lo, ray.hi, slot.s, slot.delta);
  RayPointsOf(box, ray.origin, ray.direction, time, slot.s, n, slot.delta, slot.pos, slot.dir, slot.time);
}

}  // namespace endorecon::render
