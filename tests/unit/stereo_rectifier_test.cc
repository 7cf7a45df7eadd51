// Rectification of the synthetic rig (distorted eyes, rotated against each other): points of the
// scene projected through the true lens models land on the same row in both rectified eyes
// (issue 16: epipolar error under 0.5 px), at the rectified camera's projection, and the window is
// centred on the principal point and inside both eyes' pixels.
#include "worker/prepare/stereo_rectifier.h"

#include <gtest/gtest.h>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/synthetic_recording_fixture.h"

namespace endorecon::testing {
namespace {

TEST(StereoRectifierTest, AlignsTheRowsOfTheSyntheticRig) {
  const prepare::StereoCalibration rig = SyntheticCalibration(RecordingOptions(320, 256, 1));
  const prepare::StereoRectifier rectifier(rig, {});
  const auto [epipolar, projection] = EpipolarAndProjectionError(rig, rectifier);
  EXPECT_LT(epipolar, 0.5);
  EXPECT_LT(epipolar, 1e-6) << "exact up to the lens model's inversion";
  EXPECT_LT(projection, 1e-6);
  EXPECT_NEAR(rectifier.camera().baseline, 5.0, 0.01);
  EXPECT_FALSE(rectifier.passthrough());
}

TEST(StereoRectifierTest, WindowIsCentredAndFilledByBothEyes) {
  const prepare::StereoCalibration rig = SyntheticCalibration(RecordingOptions(320, 256, 1));
  const prepare::StereoRectifier rectifier(rig, {});
  const cv::Size size = rectifier.camera().size;
  EXPECT_EQ(size.width % 2, 0);
  EXPECT_GT(size.width, 280) << "the crop keeps most of the view";
  EXPECT_NEAR(static_cast<double>(size.width) / size.height, 320.0 / 256, 0.02);
  // A white raw frame stays white everywhere in both rectified eyes: no pixel from outside.
  const cv::Mat white(256, 320, CV_8UC3, cv::Scalar::all(255));
  for (const cv::Mat& eye : {rectifier.Left(white), rectifier.Right(white)}) {
    double lowest = 0;
    cv::minMaxLoc(eye.reshape(1), &lowest);
    EXPECT_EQ(lowest, 255);
  }
}

TEST(StereoRectifierTest, OutputSizeScalesTheFocalLength) {
  const prepare::StereoCalibration rig = SyntheticCalibration(RecordingOptions(320, 256, 1));
  const prepare::StereoRectifier full(rig, {}), half(rig, {150, 120});
  EXPECT_EQ(half.camera().size, cv::Size(150, 120));
  EXPECT_LT(half.camera().scale, 0.55);
  const auto [epipolar, projection] = EpipolarAndProjectionError(rig, half);
  EXPECT_LT(epipolar, 1e-6);
  EXPECT_LT(projection, 1e-6);
  const cv::Mat white(256, 320, CV_8UC3, cv::Scalar::all(255));
  double lowest = 0;
  cv::minMaxLoc(half.Left(white).reshape(1), &lowest);
  EXPECT_EQ(lowest, 255);
}

TEST(StereoRectifierTest, RectifiedInputPassesThroughUntouched) {
  const prepare::StereoCalibration c = prepare::RectifiedCalibration({64, 48}, 60, 2);
  const prepare::StereoRectifier same(c, {});
  EXPECT_TRUE(same.passthrough());
  EXPECT_EQ(same.camera().size, cv::Size(64, 48));
  EXPECT_EQ(same.camera().focal, 60);
  cv::Mat image(48, 64, CV_8UC3);
  cv::randu(image, 0, 255);
  EXPECT_EQ(cv::norm(same.Left(image), image, cv::NORM_INF), 0);
  const prepare::StereoRectifier smaller(c, {32, 24});
  EXPECT_FALSE(smaller.passthrough());
  EXPECT_NEAR(smaller.camera().focal, 30, 1e-6);
}

TEST(StereoRectifierTest, RefusesAnotherRigsCalibration) {
  prepare::StereoCalibration rig = SyntheticCalibration(RecordingOptions(320, 256, 1));
  rig.t = cv::Vec3d(0, 0, -5);  // eyes one behind the other share no usable window
  ErrorFrom([&] { prepare::StereoRectifier(rig, {}); });
}

TEST(StereoRectifierTest, RefusesEyesOneAboveTheOther) {
  prepare::StereoCalibration rig = SyntheticCalibration(RecordingOptions(320, 256, 1));
  rig.source = "calib.yaml";
  rig.t = cv::Vec3d(0, -5, 0);
  const std::string error = ErrorFrom([&] { prepare::StereoRectifier(rig, {}); });
  EXPECT_NE(error.find("calib.yaml: T = (0, -5, 0) puts the eyes one above the other"), std::string::npos)
      << error;
}

TEST(StereoRectifierTest, RefusesARightEyeOnTheLeft) {
  prepare::StereoCalibration rig = SyntheticCalibration(RecordingOptions(320, 256, 1));
  rig.source = "calib.yaml";
  rig.t = -rig.t;  // T's sign flipped, or the eyes given the other way round
  const std::string error = ErrorFrom([&] { prepare::StereoRectifier(rig, {}); });
  EXPECT_NE(error.find("calib.yaml: T = (5"), std::string::npos) << error;
  EXPECT_NE(error.find("puts the right eye to the left of the left eye (after rectification the baseline "
                       "is -5"),
            std::string::npos)
      << error;
}

}  // namespace
}  // namespace endorecon::testing
