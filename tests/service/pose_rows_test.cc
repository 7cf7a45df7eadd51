#include "common/pose_rows.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "common/camera_values.h"
#include "common/clip_files.h"
#include "common/error.h"
#include "common/npy.h"
#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {

using testing::ErrorFrom;
using testing::TempDir;

// An LLFF row: rotation columns [down, right, back] = identity here, t, H, W, f, near, far.
std::vector<double> Row(double tx, double near, double far, double h = 48, double w = 64) {
  return {1, 0, 0, tx, h, 0, 1, 0, 0, w, 0, 0, 1, 0, 50, near, far};
}

TEST(PoseRowsTest, RowsTurnIntoOpenGlCamerasWithTheBoundsOverAllRows) {
  TempDir dir;
  std::vector<double> values = Row(0.5, 2, 10);
  const std::vector<double> second = Row(-1, 1, 12);
  values.insert(values.end(), second.begin(), second.end());
  WriteNpyFloat64(dir.path() / "poses_bounds.npy", values.data(), {2, kPoseColumns});
  const PoseRows poses = ReadPoseRows(dir.path() / "poses_bounds.npy");
  ASSERT_EQ(poses.rows.size(), 2u);
  const PoseRow& row = poses.rows[0];
  EXPECT_EQ(row.width, 64);
  EXPECT_EQ(row.height, 48);
  EXPECT_EQ(row.focal, 50);
  // Columns [down, right, back] = e_x, e_y, e_z become [right, up, back] = e_y, -e_x, e_z.
  const double expected[12] = {0, 1, 0, -1, 0, 0, 0, 0, 1, 0.5, 0, 0};
  for (int i = 0; i < 12; ++i) EXPECT_EQ(row.c2w[i], expected[i]) << i;
  EXPECT_EQ(poses.near, 1);
  EXPECT_EQ(poses.far, 12);
}

TEST(PoseRowsTest, EachRowIsCheckedNamingIt) {
  TempDir dir;
  const auto path = dir.path() / "poses_bounds.npy";
  const auto write = [&](std::vector<double> second) {
    std::vector<double> values = Row(0, 1, 10);
    values.insert(values.end(), second.begin(), second.end());
    WriteNpyFloat64(path, values.data(), {2, kPoseColumns});
  };
  write(Row(0, 1, 10, 48, 63.5));
  EXPECT_NE(ErrorFrom([&] {
              ReadPoseRows(path);
            }).find("row 1: H and W must be positive integers (H = 48, W = 63.5)"),
            std::string::npos);
  write(Row(0, 1, 10, 40, 64));
  EXPECT_NE(ErrorFrom([&] { ReadPoseRows(path); }).find("row 1: image size 64x40 differs from row 0's 64x48"),
            std::string::npos);
  write(Row(0, 10, 1));
  EXPECT_NE(
      ErrorFrom([&] { ReadPoseRows(path); }).find("row 1: depth bounds must be finite with 0 <= near < far"),
      std::string::npos);
  std::vector<double> flat = Row(0, 1, 10);
  flat[14] = 1e-3;  // a focal length in metres: a field of view near 180 degrees
  write(flat);
  EXPECT_NE(ErrorFrom([&] {
              ReadPoseRows(path);
            }).find("row 1: the focal length (fx = 0.001, fy = 0.001) gives a field of view"),
            std::string::npos);
  std::vector<double> mirrored = Row(0, 1, 10);
  mirrored[12] = -1;  // the back axis flipped: a reflection
  write(mirrored);
  EXPECT_NE(ErrorFrom([&] {
              ReadPoseRows(path);
            }).find("row 1: the pose's rotation has determinant -1 (a reflection)"),
            std::string::npos);
}

TEST(CameraValuesTest, RigidPosesAreOrthonormalProperAndNearTheOrigin) {
  // Column by column: a rotation of 90 degrees about z, centre (1, 2, 3).
  const double turned[12] = {0, 1, 0, -1, 0, 0, 0, 0, 1, 1, 2, 3};
  EXPECT_NO_THROW(CheckRigidPose(turned, "here"));
  double stretched[12];
  std::copy(turned, turned + 12, stretched);
  stretched[1] = 1.1;
  EXPECT_EQ(ErrorFrom([&] { CheckRigidPose(stretched, "here"); }),
            "here: the pose's rotation is not orthonormal (max |RᵀR − I| = 0.21)");
  double far_away[12];
  std::copy(turned, turned + 12, far_away);
  far_away[11] = 1e200;  // its square overflows; the distance does not
  EXPECT_NE(ErrorFrom([&] {
              CheckRigidPose(far_away, "here");
            }).find("the camera's centre lies 1e+200 from the origin"),
            std::string::npos);
  double broken[12];
  std::copy(turned, turned + 12, broken);
  broken[4] = NAN;
  EXPECT_EQ(ErrorFrom([&] { CheckRigidPose(broken, "here"); }), "here: the pose has non-finite entries");
}

TEST(CameraValuesTest, IntrinsicsAndBounds) {
  EXPECT_NO_THROW(CheckIntrinsics(50, 60, 32, 24, 64, 48, "here"));
  EXPECT_NE(ErrorFrom([] {
              CheckIntrinsics(50, 50, 5000, 24, 64, 48, "here");
            }).find("lies outside the 64x48 frame"),
            std::string::npos);
  EXPECT_NE(ErrorFrom([] { CheckIntrinsics(50, 500, 32, 24, 64, 48, "here"); }).find("fy / fx is 10"),
            std::string::npos);
  EXPECT_NO_THROW(CheckNearFar(0, 1, "here"));
  EXPECT_NE(ErrorFrom([] { CheckNearFar(1, 1 + 1e-6, "here"); }).find("too thin to sample"),
            std::string::npos);
  EXPECT_NE(ErrorFrom([] { CheckNearFar(1, 1e13, "here"); }).find("implausible units"), std::string::npos);
}

}  // namespace
}  // namespace endorecon
