#include "worker/engine/eval/surface_grid.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "common/error.h"
#include "worker/engine/eval/point_cloud.h"

namespace endorecon::eval {
namespace {

scene::Camera Camera(int width, int height) {
  scene::Camera camera;
  camera.width = width;
  camera.height = height;
  camera.fx = camera.fy = 5.0;
  camera.cx = width / 2.0;
  camera.cy = height / 2.0;
  camera.c2w.col(3) = Eigen::Vector3d(1, 2, 3);
  return camera;
}

TEST(SurfaceGridTest, StrideFitsThePointBudgetAndSixteenBitIndices) {
  EXPECT_EQ(SurfaceStride(160, 128, 48, 600000), 2);  // 20480 points a frame would be 983,040 in all
  EXPECT_EQ(SurfaceStride(160, 128, 1, 600000), 1);
  EXPECT_EQ(SurfaceStride(640, 512, 1, 600000), 3);  // 81,920 points at stride 2 exceed 16-bit indices
  const int s = SurfaceStride(640, 512, 156, 600000);
  EXPECT_LE(std::size_t((640 + s - 1) / s) * ((512 + s - 1) / s) * 156, 600000u);
  EXPECT_GT(std::size_t((640 + s - 2) / (s - 1)) * ((512 + s - 2) / (s - 1)) * 156, 600000u)
      << "the smallest";
  EXPECT_GE(SurfaceStride(10, 10, 1000, 1), 10) << "a budget below one point a frame gives one point";
}

// What report.html does with a grid point (surface_viewer.js): its pixel's ray, with unit z-depth,
// times the decoded depth.
Eigen::Vector3d PagePoint(const SurfaceGrid& grid, const scene::Camera& camera, int i, int j) {
  const std::size_t g = static_cast<std::size_t>(j) * grid.width + i;
  const double z = grid.depth_origin + grid.depth[g] * grid.depth_step;
  const int u = SurfacePixel(i, grid.stride, camera.width), v = SurfacePixel(j, grid.stride, camera.height);
  const Eigen::Vector3d ray((u + 0.5 - camera.cx) / camera.fx, -(v + 0.5 - camera.cy) / camera.fy, -1.0);
  return camera.c2w.col(3) + z * (camera.c2w.leftCols<3>() * ray);
}

TEST(SurfaceGridTest, ThePagesPointsAreTheBackProjectedDepthWithinQuantisation) {
  scene::Camera camera = Camera(6, 4);
  camera.c2w.leftCols<3>() << 0, 0, 1, 0, 1, 0, -1, 0, 0;  // a turned camera: rotation matters
  std::vector<float> depth(24), rgb_float(72, 0.0f);
  for (int p = 0; p < 24; ++p) depth[p] = 10.0f + 0.5f * float(p);
  std::vector<std::uint8_t> rgb(72, 0);
  rgb[3 * 7] = 200;
  const SurfaceGrid grid = SampleSurface(camera, depth, rgb, {}, 1.0, {}, 1);
  ASSERT_EQ(grid.width, 6);
  ASSERT_EQ(grid.height, 4);
  EXPECT_DOUBLE_EQ(grid.depth_origin, 10.0);
  const PointCloud cloud = BackProject(camera, depth, rgb_float, {});
  ASSERT_EQ(cloud.size(), 24u);
  // Half a quantisation step of depth along a ray of length at most |(ray)| ~ 1.6.
  const double tolerance = grid.depth_step * 0.5 * 1.7 + 1e-5;
  for (int j = 0; j < 4; ++j) {
    for (int i = 0; i < 6; ++i) {
      const Eigen::Vector3d point = PagePoint(grid, camera, i, j);
      for (int a = 0; a < 3; ++a)
        EXPECT_NEAR(point[a], cloud.xyz[3 * (j * 6 + i) + a], tolerance) << i << "," << j;
    }
  }
  EXPECT_EQ(grid.rgb[3 * 7], 200);
  EXPECT_EQ(grid.uncertainty[7], 0) << "no uncertainty map: level 0";
}

TEST(SurfaceGridTest, StrideSamplesPixelCentresOfItsBlocks) {
  const scene::Camera camera = Camera(5, 3);
  std::vector<float> depth(15);
  for (int p = 0; p < 15; ++p) depth[p] = 1.0f + float(p);
  std::vector<std::uint8_t> rgb(45);
  for (int p = 0; p < 15; ++p) rgb[3 * p] = std::uint8_t(p);
  const SurfaceGrid grid = SampleSurface(camera, depth, rgb, {}, 1.0, {}, 2);
  EXPECT_EQ(grid.stride, 2);
  ASSERT_EQ(grid.width, 3);
  ASSERT_EQ(grid.height, 2);
  // Grid (i, j) -> pixel (min(2i + 1, 4), min(2j + 1, 2)).
  const int expected[6] = {1 * 5 + 1, 1 * 5 + 3, 1 * 5 + 4, 2 * 5 + 1, 2 * 5 + 3, 2 * 5 + 4};
  for (int g = 0; g < 6; ++g) EXPECT_EQ(grid.rgb[3 * g], expected[g]) << g;
}

TEST(SurfaceGridTest, ToolPixelsAndMissingDepthHaveNoPoint) {
  const scene::Camera camera = Camera(4, 1);
  const std::vector<float> depth = {5.0f, 0.0f, std::numeric_limits<float>::quiet_NaN(), 5.0f};
  const std::vector<std::uint8_t> mask = {0, 0, 0, 1};
  const SurfaceGrid grid = SampleSurface(camera, depth, std::vector<std::uint8_t>(12, 0), {}, 1.0, mask, 1);
  EXPECT_NE(grid.depth[0], SurfaceGrid::kNoDepth);
  for (int g = 1; g < 4; ++g) EXPECT_EQ(grid.depth[g], SurfaceGrid::kNoDepth) << g;
}

TEST(SurfaceGridTest, UncertaintyIsScaledByTheBoundAndClamped) {
  const scene::Camera camera = Camera(4, 1);
  const std::vector<float> uncertainty = {0.0f, 0.5f, 2.0f, std::numeric_limits<float>::infinity()};
  const SurfaceGrid grid = SampleSurface(camera, std::vector<float>(4, 3.0f),
                                         std::vector<std::uint8_t>(12, 0), uncertainty, 1.0, {}, 1);
  EXPECT_EQ(grid.uncertainty, (std::vector<std::uint8_t>{0, 128, 255, 0}));
}

TEST(SurfaceGridTest, AHeatMapIsSampledAtTheGridsPixels) {
  const scene::Camera camera = Camera(4, 3);
  // Stride 2: grid columns sample pixels 1 and 3, rows 1 and 2 (the last row, clamped).
  std::vector<float> values(12, 0.0f);
  values[1 * 4 + 1] = 0.25f;
  values[1 * 4 + 3] = 4.0f;
  values[2 * 4 + 1] = std::numeric_limits<float>::quiet_NaN();
  values[2 * 4 + 3] = 1.0f;
  EXPECT_EQ(SampleHeat(camera, values, 2.0, 2), (std::vector<std::uint8_t>{32, 255, 0, 128}));
  EXPECT_EQ(SampleHeat(camera, {}, 2.0, 2), std::vector<std::uint8_t>(4, 0));
  EXPECT_THROW(SampleHeat(camera, std::vector<float>(5), 1.0, 1), Error);
  EXPECT_THROW(SampleHeat(camera, values, 0.0, 1), Error);
  EXPECT_THROW(SampleHeat(camera, values, 1.0, 0), Error);
}

TEST(SurfaceGridTest, BadSizesAreRefused) {
  const scene::Camera camera = Camera(4, 2);
  const std::vector<float> depth(8, 1.0f);
  const std::vector<std::uint8_t> rgb(24, 0);
  EXPECT_THROW(SampleSurface(camera, std::vector<float>(7, 1.0f), rgb, {}, 1.0, {}, 1), Error);
  EXPECT_THROW(SampleSurface(camera, depth, std::vector<std::uint8_t>(23, 0), {}, 1.0, {}, 1), Error);
  EXPECT_THROW(SampleSurface(camera, depth, rgb, std::vector<float>(3, 0.0f), 1.0, {}, 1), Error);
  EXPECT_THROW(SampleSurface(camera, depth, rgb, {}, 1.0, std::vector<std::uint8_t>(3, 0), 1), Error);
  EXPECT_THROW(SampleSurface(camera, depth, rgb, {}, 1.0, {}, 0), Error);
  EXPECT_THROW(SampleSurface(camera, depth, rgb, {}, 0.0, {}, 1), Error);
}

}  // namespace
}  // namespace endorecon::eval
