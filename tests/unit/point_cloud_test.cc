#include "worker/engine/eval/point_cloud.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "common/error.h"

namespace endorecon::eval {
namespace {

scene::Camera SmallCamera() {
  scene::Camera camera;
  camera.width = 4;
  camera.height = 3;
  camera.fx = camera.fy = 2.0;
  camera.cx = 2.0;
  camera.cy = 1.5;
  return camera;
}

TEST(PointCloud, DepthIsZDepthAlongTheOpticalAxis) {
  scene::Camera camera = SmallCamera();
  camera.c2w.col(3) = Eigen::Vector3d(10, 20, 30);
  const std::vector<float> depth(12, 5.0f);
  std::vector<float> rgb(36, 0.5f);
  rgb[3 * 7] = 1.0f;
  const PointCloud cloud = BackProject(camera, depth, rgb, {});
  ASSERT_EQ(cloud.size(), 12u);
  // Pixel (u=3, v=1): camera direction ((3.5 - 2) / 2, -(1.5 - 1.5) / 2, -1) = (0.75, 0, -1).
  EXPECT_NEAR(cloud.xyz[3 * 7 + 0], 10 + 5 * 0.75, 1e-5);
  EXPECT_NEAR(cloud.xyz[3 * 7 + 1], 20, 1e-5);
  EXPECT_NEAR(cloud.xyz[3 * 7 + 2], 30 - 5, 1e-5);  // OpenGL: the camera looks down -z
  EXPECT_EQ(cloud.rgb[3 * 7], 255);
  EXPECT_EQ(cloud.rgb[3 * 7 + 1], 128);
}

TEST(PointCloud, RotatedCameraMovesPointsWithIt) {
  scene::Camera camera = SmallCamera();
  camera.c2w.leftCols<3>() << 0, 0, 1, 0, 1, 0, -1, 0, 0;  // camera's -z looks along world -x
  const std::vector<float> depth(12, 2.0f);
  const PointCloud cloud = BackProject(camera, depth, std::vector<float>(36, 0.0f), {});
  // Pixel (u=1, v=1): camera direction (-0.25, 0, -1) -> world (-1, 0, 0.25).
  EXPECT_NEAR(cloud.xyz[3 * 5 + 0], -2.0, 1e-5);
  EXPECT_NEAR(cloud.xyz[3 * 5 + 2], 0.5, 1e-5);
}

TEST(PointCloud, ToolPixelsAndMissingDepthAreLeftOut) {
  const scene::Camera camera = SmallCamera();
  std::vector<float> depth(12, 1.0f);
  depth[1] = 0.0f;
  depth[2] = std::nanf("");
  std::vector<std::uint8_t> mask(12, 0);
  mask[3] = 1;
  const PointCloud cloud = BackProject(camera, depth, std::vector<float>(36, 0.0f), mask);
  EXPECT_EQ(cloud.size(), 9u);
  EXPECT_EQ(cloud.rgb.size(), 27u);
  EXPECT_THROW(BackProject(camera, std::vector<float>(11), std::vector<float>(36), {}), Error);
}

}  // namespace
}  // namespace endorecon::eval
