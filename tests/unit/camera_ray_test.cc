// The part of a ray the field is sampled on: [near, far] cut to the scene box.
#include "worker/engine/render/camera_ray.h"

#include <gtest/gtest.h>

namespace endorecon::render {
namespace {

scene::BoxFrame UnitBoxAround(double half) {
  scene::BoxFrame box;
  for (int c = 0; c < 3; ++c) {
    box.min[c] = -half;
    box.inv_size[c] = 1.0 / (2 * half);
  }
  box.scale = 2 * half;
  return box;
}

TEST(CameraRayTest, BoxSpanCutsNearAndFarToTheBox) {
  const scene::BoxFrame box = UnitBoxAround(1.0);
  const double origin[3] = {0, 0, 4}, down[3] = {0, 0, -1};
  double lo = 0, hi = 0;
  BoxSpan(box, origin, down, 2.0, 6.0, &lo, &hi);  // enters at z = 1 (s = 3), leaves at z = -1 (s = 5)
  EXPECT_DOUBLE_EQ(lo, 3.0);
  EXPECT_DOUBLE_EQ(hi, 5.0);
  BoxSpan(box, origin, down, 3.5, 4.5, &lo, &hi);  // already inside: unchanged
  EXPECT_DOUBLE_EQ(lo, 3.5);
  EXPECT_DOUBLE_EQ(hi, 4.5);
  const double slanted[3] = {0.5, 0, -1};  // leaves through x = 1 at s = 2 before reaching z = 1
  BoxSpan(box, origin, slanted, 2.0, 6.0, &lo, &hi);
  EXPECT_EQ(lo, hi) << "a ray that misses the box gets an empty span";
  EXPECT_DOUBLE_EQ(lo, 2.0);
  const double beside[3] = {3, 0, 4};  // parallel to the x and y slabs, outside x
  BoxSpan(box, beside, down, 2.0, 6.0, &lo, &hi);
  EXPECT_EQ(lo, hi);
}

TEST(CameraRayTest, RaysOfAFrustumBoxAreNotCut) {
  // Every ray of a camera whose frustum the box holds keeps [near, far].
  scene::Camera camera;
  camera.width = 16;
  camera.height = 12;
  camera.fx = camera.fy = 14;
  camera.cx = 8;
  camera.cy = 6;
  const scene::SceneBox box = scene::FrustumBox({camera}, 1.0, 9.0);
  for (int pixel = 0; pixel < camera.width * camera.height; ++pixel) {
    const CameraRay ray = CameraRayOf(camera, pixel, box, nullptr, 1.0, 9.0);
    ASSERT_FLOAT_EQ(ray.lo, 1.0f) << pixel;
    ASSERT_FLOAT_EQ(ray.hi, 9.0f) << pixel;
  }
}

}  // namespace
}  // namespace endorecon::render
