// A mono endoscope's turns from its frames: the least-squares rotation between rays, and the turns
// of a camera turning in front of a textured surface through a round scope, recovered to a small
// fraction of a degree with the black rim left out; a frame with nothing to track keeps the turn
// before it.
#include "worker/prepare/camera_rotation.h"

#include <gtest/gtest.h>

#include <opencv2/calib3d.hpp>

#include "tests/unit/turning_camera_frames.h"

namespace endorecon::prepare {
namespace {

using testing::AngleBetweenDeg;

TEST(CameraRotationTest, FitRotationRecoversAKnownRotationFromNoisyRays) {
  cv::Matx33d truth;
  cv::Rodrigues(cv::Vec3d(0.1, -0.3, 0.2), truth);
  cv::RNG random(3);
  std::vector<cv::Vec3d> from, to;
  for (int i = 0; i < 50; ++i) {
    const cv::Vec3d ray = cv::normalize(cv::Vec3d(random.uniform(-0.5, 0.5), random.uniform(-0.4, 0.4), 1.0));
    from.push_back(ray);
    to.push_back(cv::normalize(truth * ray + cv::Vec3d(random.gaussian(1e-4), random.gaussian(1e-4), 0)));
  }
  const cv::Matx33d fitted = FitRotation(from, to);
  EXPECT_LT(AngleBetweenDeg(fitted, truth), 0.01);
  EXPECT_NEAR(cv::determinant(fitted), 1.0, 1e-9);
  // Two rays fix it exactly.
  EXPECT_LT(AngleBetweenDeg(FitRotation({from[0], from[1]}, {truth * from[0], truth * from[1]}), truth),
            1e-6);
}

TEST(CameraRotationTest, TurnsOfACameraBehindARoundScopeAreRecovered) {
  // Twelve frames turning away (past where the first frame's corners are still followed) and back.
  std::vector<cv::Vec3d> path;
  for (int f = 1; f < 12; ++f) {
    const double s = f < 7 ? f : 12 - f;
    path.emplace_back(0.3 * s, 3.0 * s, 1.5 * s);
  }
  const auto scope = testing::MakeTurningCamera({320, 180}, path);
  cv::Mat outside;
  cv::inRange(scope.frames[0], cv::Scalar::all(0), cv::Scalar::all(0), outside);
  const CameraTurns turns = EstimateCameraTurns(scope.frames, scope.camera, outside);
  ASSERT_EQ(turns.rotations.size(), scope.frames.size());
  EXPECT_EQ(turns.unplaced, 0);
  for (std::size_t f = 0; f < scope.frames.size(); ++f) {
    EXPECT_LT(AngleBetweenDeg(turns.rotations[f], scope.turns[f]), 0.05) << "frame " << f;
  }
  for (std::size_t f = 0; f + 1 < scope.frames.size(); ++f) {
    EXPECT_LT(turns.residual_px[f], 0.5) << "frame " << f + 1;
    EXPECT_GT(turns.inliers[f], 30) << "frame " << f + 1;
  }
}

TEST(CameraRotationTest, AFrameWithNothingToTrackKeepsTheTurnBeforeIt) {
  auto scope = testing::MakeTurningCamera({320, 180}, {{0, 2, 0}, {0, 4, 0}});
  scope.frames[2].setTo(cv::Scalar::all(90));  // a flat frame: no corners
  const CameraTurns turns = EstimateCameraTurns(scope.frames, scope.camera, cv::Mat());
  EXPECT_EQ(turns.unplaced, 1);
  EXPECT_EQ(turns.inliers[1], 0);
  EXPECT_LT(AngleBetweenDeg(turns.rotations[2], turns.rotations[1]), 1e-9);
  EXPECT_LT(AngleBetweenDeg(turns.rotations[1], scope.turns[1]), 0.15);
}

}  // namespace
}  // namespace endorecon::prepare
