// A mono endoscope's turns from its frames: the least-squares rotation between rays, the rotations
// that best agree with turns fitted between many pairs of frames (less drift than a chain, robust to a
// wrong pair), and the turns of a camera turning in front of a textured surface through a round scope,
// recovered to a small fraction of a degree with the black rim left out; a frame with nothing to
// track keeps the turn before it.
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

cv::Matx33d Turned(const cv::Vec3d& axis_angle) {
  cv::Matx33d r;
  cv::Rodrigues(axis_angle, r);
  return r;
}

// Forty frames on a random walk of turns, and turns between frames 1, 2, 4 and 8 apart, each off by
// 0.2 degrees of noise, one of them 10 degrees wrong: the averaged rotations are closer to the truth
// than the chain of neighbours they start from, everywhere within half a degree.
TEST(CameraRotationTest, AveragingManyPairsDriftsLessThanTheChain) {
  constexpr int kFrames = 40;
  constexpr double kDeg = CV_PI / 180;
  cv::RNG random(11);
  std::vector<cv::Matx33d> truth = {cv::Matx33d::eye()};
  for (int f = 1; f < kFrames; ++f) {
    truth.push_back(
        truth.back() *
        Turned(cv::Vec3d(random.gaussian(1.0), random.gaussian(1.0), random.gaussian(0.3)) * kDeg));
  }
  const auto noisy = [&](int i, int j) {
    const cv::Vec3d noise(random.gaussian(0.2), random.gaussian(0.2), random.gaussian(0.2));
    return PairTurn{i, j, truth[i].t() * truth[j] * Turned(noise * kDeg)};
  };
  std::vector<PairTurn> pairs;
  std::vector<cv::Matx33d> chain = {cv::Matx33d::eye()};
  for (int j = 1; j < kFrames; ++j) {
    for (int gap : {1, 2, 4, 8}) {
      if (j - gap < 0) break;
      pairs.push_back(noisy(j - gap, j));
      if (gap == 1) chain.push_back(chain.back() * pairs.back().turn);
    }
  }
  pairs[30].turn = pairs[30].turn * Turned(cv::Vec3d(10 * kDeg, 0, 0));  // a wrong fit
  const std::vector<cv::Matx33d> averaged = AverageTurns(pairs, chain);
  ASSERT_EQ(averaged.size(), truth.size());
  EXPECT_LT(AngleBetweenDeg(averaged[0], cv::Matx33d::eye()), 1e-12) << "the first frame is the world";
  double chain_error = 0, averaged_error = 0;
  for (int f = 0; f < kFrames; ++f) {
    chain_error += AngleBetweenDeg(chain[f], truth[f]) / kFrames;
    averaged_error += AngleBetweenDeg(averaged[f], truth[f]) / kFrames;
    EXPECT_LT(AngleBetweenDeg(averaged[f], truth[f]), 0.5) << "frame " << f;
  }
  EXPECT_LT(averaged_error, 0.6 * chain_error) << averaged_error << " against the chain's " << chain_error;
}

// Pairs without noise give the truth back from a start off by degrees; a frame no pair reaches keeps
// its start.
TEST(CameraRotationTest, AveragingExactPairsRecoversTheTruth) {
  const std::vector<cv::Matx33d> truth = {cv::Matx33d::eye(), Turned({0.05, 0, 0}), Turned({0.05, 0.1, 0}),
                                          Turned({0, 0.1, 0.02}), Turned({0.3, 0.2, 0.1})};
  std::vector<PairTurn> pairs;
  for (int j = 1; j < 4; ++j) {
    for (int i = 0; i < j; ++i) pairs.push_back({i, j, truth[i].t() * truth[j]});
  }
  std::vector<cv::Matx33d> start = truth;
  for (int f = 1; f < 5; ++f) start[f] = start[f] * Turned({0.03, -0.02, 0.04});
  const std::vector<cv::Matx33d> averaged = AverageTurns(pairs, start);
  for (int f = 0; f < 4; ++f) EXPECT_LT(AngleBetweenDeg(averaged[f], truth[f]), 1e-6) << "frame " << f;
  EXPECT_LT(AngleBetweenDeg(averaged[4], start[4]), 1e-6) << "frame 4: no pair reaches it";
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
