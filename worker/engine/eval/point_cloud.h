// A coloured point cloud of the tissue surface seen in one rendered frame.
#pragma once

#include <cstddef>
#include <cstdint>
#include <span>
#include <vector>

#include "worker/engine/scene/camera.h"

namespace endorecon::eval {

struct PointCloud {
  std::vector<float> xyz;         // 3 per point, world coordinates, clip units
  std::vector<std::uint8_t> rgb;  // 3 per point
  std::size_t size() const { return xyz.size() / 3; }
};

// Back-projects every tissue pixel (tool_mask empty or 0; 1 = tool) with a finite depth > 0:
// point = origin + depth * direction of camera.Ray(u, v), whose direction has unit z-depth, so
// `depth` (camera.width * camera.height, z-depth along the optical axis) is used as it is.
// Colours come from `rgb` (float RGB, clamped to [0, 1], rounded to 8 bits). Points follow pixel
// order, row by row. Throws InvalidArgument when a size disagrees with the camera's.
PointCloud BackProject(const scene::Camera& camera, std::span<const float> depth, std::span<const float> rgb,
                       std::span<const std::uint8_t> tool_mask);

}  // namespace endorecon::eval
