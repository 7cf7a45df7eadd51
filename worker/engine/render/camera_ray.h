// The one way a pixel becomes samples for the field, shared by training, depth refinement and
// rendering: the camera ray of the pixel, the part of [near, far] worth sampling (its occupied span
// when an occupancy grid is given), a sampler that places depths and intervals there, and RayPoints,
// which turns them into field inputs.
#pragma once

#include <Eigen/Core>

#include "worker/engine/render/occupancy_grid.h"
#include "worker/engine/render/ray_points.h"
#include "worker/engine/scene/camera.h"
#include "worker/engine/scene/scene_box.h"

namespace endorecon::render {

// A pixel's ray (origin, direction with unit z-depth, as scene::Camera::Ray) and its span [lo, hi].
struct CameraRay {
  Eigen::Vector3d origin, direction;
  float lo = 0, hi = 1;
};

// The ray of `pixel` (row-major index) of `camera`; its span is [near, far], or the occupied span of
// that range when `occupancy` is not null (an empty grid leaves the whole range).
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
inline RaySlot RaySlotOf(float* s, float* delta, float* pos, float* dir, float* time, int r, int n) {
  const std::size_t o = static_cast<std::size_t>(r) * n;
  return {s + o, delta + o, pos + 3 * o, dir + 3 * o, time + o};
}

// sample(lo, hi, s, delta) places the ray's n samples within its span; RayPoints then makes them
// field inputs at `time` (intervals rescaled to box units).
template <typename Sample>
void PlaceSamples(const CameraRay& ray, const scene::SceneBox& box, float time, int n, Sample&& sample,
                  const RaySlot& slot) {
  sample(ray.lo, ray.hi, slot.s, slot.delta);
  RayPoints(box, ray.origin, ray.direction, time, slot.s, n, slot.delta, slot.pos, slot.dir, slot.time);
}

}  // namespace endorecon::render
