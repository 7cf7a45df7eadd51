#include "worker/engine/eval/point_cloud.h"

#include <cmath>

#include "worker/engine/eval/image_size.h"
#include "worker/engine/eval/quantize.h"

namespace endorecon::eval {

PointCloud BackProject(const scene::Camera& camera, std::span<const float> depth, std::span<const float> rgb,
                       std::span<const std::uint8_t> tool_mask) {
  const int w = camera.width, h = camera.height;
  CheckImageSize(depth.size(), w, h, 1, "point cloud: depth");
  CheckImageSize(rgb.size(), w, h, 3, "point cloud: colour");
  CheckMaskSize(tool_mask.size(), w, h, "point cloud: tool mask");
  PointCloud cloud;
  Eigen::Vector3d origin, direction;
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const std::size_t p = static_cast<std::size_t>(v) * w + u;
      if ((!tool_mask.empty() && tool_mask[p] != 0) || !std::isfinite(depth[p]) || depth[p] <= 0) continue;
      camera.Ray(u, v, origin, direction);
      const Eigen::Vector3d point = origin + static_cast<double>(depth[p]) * direction;
      for (int c = 0; c < 3; ++c) {
        cloud.xyz.push_back(static_cast<float>(point[c]));
        cloud.rgb.push_back(ToByte(rgb[3 * p + c]));
      }
    }
  }
  return cloud;
}

}  // namespace endorecon::eval
