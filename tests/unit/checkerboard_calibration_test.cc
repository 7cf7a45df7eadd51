// `calibrate` on the synthetic rig's checkerboard views: the RMS reprojection error is small, the
// rig comes back, and rectifying with the estimate keeps the true rig's rows aligned to within a
// pixel (see below).
#include "worker/prepare/checkerboard_calibration.h"

#include <gtest/gtest.h>
#include <spdlog/sinks/ostream_sink.h>
#include <spdlog/spdlog.h>

#include <memory>
#include <sstream>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/synthetic_recording_fixture.h"

namespace endorecon::testing {
namespace {

// The synthetic recording's board.
prepare::CheckerboardOptions SyntheticBoard() {
  prepare::CheckerboardOptions board;
  board.inner_corners = {scene::kCheckerboardColumns, scene::kCheckerboardRows};
  board.square = scene::kCheckerboardSquare;
  return board;
}

TEST(CheckerboardCalibrationTest, RecoversTheSyntheticRig) {
  TempDir dir("checkerboard");
  scene::SynthOptions options = RecordingOptions(320, 256, 1, 24);
  scene::WriteSyntheticClip(options, dir / "synth");
  const prepare::CheckerboardOptions board = SyntheticBoard();
  const prepare::RecordingInput recording{prepare::StereoLayout::kTwoSources,
                                          dir / "synth/recording/checkerboard/left",
                                          dir / "synth/recording/checkerboard/right",
                                          {}};
  const prepare::CheckerboardCalibration result = prepare::CalibrateFromCheckerboard(recording, board);
  EXPECT_EQ(result.frames_read, options.checkerboard_views);
  EXPECT_GE(result.views_used, options.checkerboard_views * 3 / 4);
  EXPECT_LT(result.rms_px, 0.5);
  EXPECT_EQ(prepare::CalibrationWarning(result, board), "");

  const prepare::StereoCalibration truth = SyntheticCalibration(options);
  const prepare::StereoCalibration& estimate = result.calibration;
  EXPECT_NEAR(estimate.k1(0, 0), truth.k1(0, 0), 0.01 * truth.k1(0, 0));
  EXPECT_NEAR(estimate.k2(1, 2), truth.k2(1, 2), 2.0);
  EXPECT_NEAR(estimate.d1.at<double>(0, 0), truth.d1.at<double>(0, 0), 0.03);
  EXPECT_NEAR(estimate.baseline(), truth.baseline(), 0.01 * truth.baseline());
  const auto [epipolar, projection] =
      EpipolarAndProjectionError(truth, prepare::StereoRectifier(estimate, {}));
  // The worst row error over the whole frame with the *estimated* calibration: 0.48 px in the GCC
  // Release build, 0.81 px in the clang (sanitizer) build, whose rounding renders the board views a
  // little differently (measured 2026-12-01). Rectifying with the true calibration stays under the
  // issue's 0.5 px (StereoRectifierTest); the estimate from 24 synthetic views is held to 1 px.
  EXPECT_LT(epipolar, 1.0);

  prepare::WriteStereoCalibration(dir / "calibration.yaml", estimate,
                                  {{"rms_reprojection_error_px", result.rms_px}});
  EXPECT_EQ(prepare::LoadStereoCalibration({dir / "calibration.yaml"}).image_size, cv::Size(320, 256));

  // A --board of fewer inner corners than the board's finds corners anyway, and calibrates badly:
  // warned of, naming the flag (it was written without a word; found 2026-12-06).
  prepare::CheckerboardOptions wrong = board;
  wrong.inner_corners = {5, 4};
  const prepare::CheckerboardCalibration bad = prepare::CalibrateFromCheckerboard(recording, wrong);
  EXPECT_GT(bad.rms_px, prepare::kMostPlausibleRmsPx);
  EXPECT_NE(
      prepare::CalibrationWarning(bad, wrong).find("check that --board 5x4 counts the board's inner corners"),
      std::string::npos)
      << prepare::CalibrationWarning(bad, wrong);
}

TEST(CheckerboardCalibrationTest, TooFewViewsOfTheBoardIsAClearError) {
  TempDir dir("checkerboard");
  scene::WriteSyntheticClip(RecordingOptions(160, 128, 1, 6), dir / "synth");
  prepare::CheckerboardOptions board;
  board.inner_corners = {7, 7};  // not this board
  board.square = 4;
  const prepare::RecordingInput recording{prepare::StereoLayout::kTwoSources,
                                          dir / "synth/recording/checkerboard/left",
                                          dir / "synth/recording/checkerboard/right",
                                          {}};
  const std::string message = ErrorFrom([&] { prepare::CalibrateFromCheckerboard(recording, board); });
  EXPECT_NE(message.find("board (inner corners) shows in both eyes in 0 of 6 frames"), std::string::npos)
      << message;
}

// Views of different moments (the left eye's recording begun a view early) calibrated each eye to
// 0.10 px alone and the pair to 16 px, a baseline of 100 for 5, written with a warning that blamed
// --board: refused, saying what to do (found 2026-12-07). Its 23 pairs are too few for the eyes'
// motion to tell (eye_sync.h), which calibrate no longer warns of: its own fit tells. So are eyes
// given the other way round.
TEST(CheckerboardCalibrationTest, ViewsOfDifferentMomentsAndSwappedEyesAreRefused) {
  TempDir dir("checkerboard");
  scene::WriteSyntheticClip(RecordingOptions(320, 256, 1, 24), dir / "synth");
  prepare::RecordingInput recording{prepare::StereoLayout::kTwoSources,
                                    dir / "synth/recording/checkerboard/left",
                                    dir / "synth/recording/checkerboard/right",
                                    {}};
  recording.skip_left = 1;
  std::ostringstream log;
  const auto sink = std::make_shared<spdlog::sinks::ostream_sink_mt>(log);
  spdlog::default_logger()->sinks().push_back(sink);
  const std::string message =
      ErrorFrom([&] { prepare::CalibrateFromCheckerboard(recording, SyntheticBoard()); });
  spdlog::default_logger()->sinks().pop_back();
  EXPECT_NE(message.find("each eye calibrates well alone"), std::string::npos) << message;
  EXPECT_NE(message.find("the eyes' views are not of the same moments"), std::string::npos) << message;
  EXPECT_NE(message.find("--skip-left or --skip-right"), std::string::npos) << message;
  EXPECT_EQ(log.str().find("too few to check"), std::string::npos) << log.str();

  // At 96 x 72 the board shows whole in few views of each eye, and one view apart in one of both:
  // said as views of different moments, not as a board too seldom seen (found 2026-12-07).
  scene::WriteSyntheticClip(RecordingOptions(96, 72, 1, 24), dir / "small");
  prepare::RecordingInput small{prepare::StereoLayout::kTwoSources,
                                dir / "small/recording/checkerboard/left",
                                dir / "small/recording/checkerboard/right",
                                {}};
  small.skip_left = 1;
  const std::string small_message =
      ErrorFrom([&] { prepare::CalibrateFromCheckerboard(small, SyntheticBoard()); });
  EXPECT_NE(small_message.find("the eyes' frames seem not to be of the same moments"), std::string::npos)
      << small_message;
  small.skip_left = 0;
  EXPECT_GT(prepare::CalibrateFromCheckerboard(small, SyntheticBoard()).views_found, 3)
      << "in step: calibrates";

  // The eyes the other way round: refused, saying so (a file `prepare` refused was written).
  const prepare::RecordingInput swapped{prepare::StereoLayout::kTwoSources,
                                        dir / "synth/recording/checkerboard/right",
                                        dir / "synth/recording/checkerboard/left",
                                        {}};
  const std::string other_way =
      ErrorFrom([&] { prepare::CalibrateFromCheckerboard(swapped, SyntheticBoard()); });
  EXPECT_NE(other_way.find("the right eye calibrates to the left of the left eye"), std::string::npos)
      << other_way;
  EXPECT_NE(other_way.find("swap --left and --right"), std::string::npos) << other_way;
}

// One eye's views given for both eyes calibrate to eyes 1e-16 apart: refused, not written for
// `prepare` to fail on later with a message about rectification (found 2026-12-05).
TEST(CheckerboardCalibrationTest, OneEyesViewsGivenTwiceAreRefused) {
  TempDir dir("checkerboard");
  scene::WriteSyntheticClip(RecordingOptions(320, 256, 1, 8), dir / "synth");
  const prepare::CheckerboardOptions board = SyntheticBoard();
  const std::filesystem::path left = dir / "synth/recording/checkerboard/left";
  // The same folder for both eyes is named as such before a view is read; a copy of it is found by
  // the calibration.
  const prepare::RecordingInput same{prepare::StereoLayout::kTwoSources, left, left, {}};
  std::string message = ErrorFrom([&] { prepare::CalibrateFromCheckerboard(same, board); });
  EXPECT_NE(message.find("the right eye is the left eye's recording"), std::string::npos) << message;
  std::filesystem::copy(left, dir / "copy");
  const prepare::RecordingInput copy{prepare::StereoLayout::kTwoSources, left, dir / "copy", {}};
  message = ErrorFrom([&] { prepare::CalibrateFromCheckerboard(copy, board); });
  EXPECT_NE(message.find("are the left and right images the same eye's?"), std::string::npos) << message;
}

}  // namespace
}  // namespace endorecon::testing
