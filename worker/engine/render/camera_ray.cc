#include "worker/engine/render/camera_ray.h"

namespace endorecon::render {

CameraRay CameraRayOf(const scene::Camera& camera, int pixel, const scene::SceneBox& box,
                      const OccupancyGrid* occupancy, double near, double far) {
  const OccupancyView cells = occupancy != nullptr && !occupancy->empty()
                                  ? OccupancyView{occupancy->cells(), occupancy->resolution()}
                                  : OccupancyView{};
  return CameraRayOfPixel(camera.View(), pixel, box.Frame(), cells, near, far);
}

}  // namespace endorecon::render
