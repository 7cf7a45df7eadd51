#include "worker/engine/render/camera_ray.h"

namespace endorecon::render {

CameraRay CameraRayOf(const scene::Camera& camera, int pixel, const scene::SceneBox& box,
                      const OccupancyGrid* occupancy, double near, double far) {
  CameraRay ray;
  camera.Ray(pixel % camera.width, pixel / camera.width, ray.origin, ray.direction);
  double lo = near, hi = far;
  if (occupancy != nullptr) occupancy->Span(box, ray.origin, ray.direction, near, far, &lo, &hi);
  ray.lo = static_cast<float>(lo);
  ray.hi = static_cast<float>(hi);
  return ray;
}

}  // namespace endorecon::render
