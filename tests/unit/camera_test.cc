// The pinhole camera: a pixel's ray and its inverse, where a world point lands.
#include "worker/engine/scene/camera.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>

namespace endorecon::scene {
namespace {

Camera TiltedCamera() {
  Camera camera;
  camera.c2w.leftCols<3>() =
      (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(-0.2, Eigen::Vector3d::UnitX()))
          .toRotationMatrix();
  camera.c2w.col(3) = Eigen::Vector3d(0.4, -0.1, 2.0);
  camera.fx = 40;
  camera.fy = 44;
  camera.cx = 15.5;
  camera.cy = 11;
  camera.width = 32;
  camera.height = 24;
  return camera;
}

TEST(CameraTest, APointOnAPixelsRayLandsAtThatPixelsCentre) {
  const Camera camera = TiltedCamera();
  Eigen::Vector3d origin, direction;
  for (const auto& [u, v] : {std::pair{0, 0}, std::pair{31, 23}, std::pair{7, 18}}) {
    camera.Ray(u, v, origin, direction);
    for (double s : {0.5, 3.0}) {
      double x = -1, y = -1;
      ASSERT_TRUE(camera.ToPixel(origin + s * direction, x, y));
      EXPECT_NEAR(x, u + 0.5, 1e-9);
      EXPECT_NEAR(y, v + 0.5, 1e-9);
    }
  }
}

TEST(CameraTest, APointBehindTheCameraLandsNowhere) {
  const Camera camera = TiltedCamera();
  Eigen::Vector3d origin, direction;
  camera.Ray(10, 10, origin, direction);
  double x = -1, y = -1;
  EXPECT_FALSE(camera.ToPixel(origin - direction, x, y));
  EXPECT_FALSE(camera.ToPixel(origin, x, y)) << "the centre itself is at depth 0";
  EXPECT_FALSE(camera.ToPixel(Eigen::Vector3d::Constant(std::nan("")), x, y));
  EXPECT_EQ(x, -1);
  EXPECT_EQ(y, -1);
}

TEST(CameraTest, CamerasAreEqualWhenPoseIntrinsicsAndSizeAre) {
  const Camera camera = TiltedCamera();
  Camera other = camera;
  EXPECT_EQ(other, camera);
  other.c2w(0, 3) += 1e-12;
  EXPECT_NE(other, camera);
  other = camera;
  other.height = 25;
  EXPECT_NE(other, camera);
}

}  // namespace
}  // namespace endorecon::scene
