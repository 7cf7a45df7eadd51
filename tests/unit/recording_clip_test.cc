// A DICOM recording turned into the engine's clip: a side-by-side stereo recording of the synthetic
// scene gets a depth prior by stereo matching, close to the generator's own depth (the synthetic
// scene has the nominal focal length and baseline a recording is assumed to have); a mono recording
// of a turning endoscope gets cameras that turn as it did, or one still camera when asked.
#include "worker/runtime/recording_clip.h"

#include <gtest/gtest.h>

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "common/dicom/recording_writer.h"
#include "common/dicom/uid.h"
#include "common/error.h"
#include "tests/unit/temp_dir.h"
#include "tests/unit/turning_camera_frames.h"
#include "worker/engine/eval/exports.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/synthetic_clip.h"

namespace endorecon::worker {
namespace {

// A synthetic stereo clip of `frames` frames of `size` in `dir`/synth, written as a side-by-side
// recording, `dir`/sbs.dcm; `moving`: the endoscope moves over a still scene.
scene::SynthOptions WriteSideBySide(const std::filesystem::path& dir, int frame_count, cv::Size size,
                                    bool moving) {
  scene::SynthOptions synth;
  synth.frames = frame_count;
  synth.width = size.width;
  synth.height = size.height;
  synth.stereo = true;
  synth.moving = moving;
  synth.static_scene = moving;
  scene::WriteSyntheticClip(synth, dir / "synth");
  std::vector<cv::Mat> frames;
  std::vector<double> times;
  for (int f = 0; f < frame_count; ++f) {
    const std::string name = eval::FrameFileName(f, ".png");
    const cv::Mat left = cv::imread((dir / "synth/images" / name).string());
    const cv::Mat right = cv::imread((dir / "synth/images_right" / name).string());
    EXPECT_FALSE(left.empty() || right.empty()) << name;
    cv::Mat both;
    cv::hconcat(left, right, both);
    frames.push_back(both);
    times.push_back(0.04 * f);
  }
  dicom::RecordingHeader header;
  header.study = dicom::NewStudyContext("P-1", "Doe^Jane", "", "");
  dicom::WriteEndoscopicFrames(frames, times, false, header, dir / "sbs.dcm");
  return synth;
}

TEST(RecordingClipTest, SideBySideRecordingGetsADepthPriorFromStereo) {
  testing::TempDir dir("recording-clip");
  const scene::SynthOptions synth = WriteSideBySide(dir.path(), 4, {160, 128}, false);

  dicom::RecordingOptions options;
  options.stereo = dicom::StereoLayout::kSideBySide;
  const auto clip = ClipFromRecording(dir / "sbs.dcm", options, dir / "clip");
  ASSERT_TRUE(clip.has_value());
  EXPECT_TRUE(std::filesystem::exists(dir / "clip/recording.json"));
  EXPECT_TRUE(std::filesystem::exists(dir / "clip/prepare.json"));

  const scene::Clip prepared = scene::LoadClip(dir / "clip");
  const scene::Clip truth = scene::LoadClip(dir / "synth");
  ASSERT_TRUE(prepared.has_depth());
  ASSERT_EQ(prepared.frame_count(), synth.frames);
  std::vector<double> errors;
  std::size_t pixels = 0;
  for (int f = 0; f < synth.frames; ++f) {
    const auto& estimate = prepared.depth[f];
    const auto& exact = truth.gt_depth.empty() ? truth.depth[f] : truth.gt_depth[f];
    ASSERT_EQ(estimate.size(), exact.size());
    pixels += estimate.size();
    for (std::size_t i = 0; i < estimate.size(); ++i) {
      if (estimate[i] > 0 && exact[i] > 0) errors.push_back(std::abs(estimate[i] - exact[i]) / exact[i]);
    }
  }
  EXPECT_GT(static_cast<double>(errors.size()) / static_cast<double>(pixels), 0.7);
  std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
  EXPECT_LT(errors[errors.size() / 2], 0.03) << "median relative depth error";
}

TEST(RecordingClipTest, SideBySideRecordingOfAMovingEndoscopeGetsItsPoses) {
  testing::TempDir dir("recording-clip-moving");
  const scene::SynthOptions synth = WriteSideBySide(dir.path(), 6, {320, 256}, true);

  dicom::RecordingOptions options;
  options.stereo = dicom::StereoLayout::kSideBySide;
  const auto recording = ClipFromRecording(dir / "sbs.dcm", options, dir / "clip");
  ASSERT_TRUE(recording.has_value());
  const scene::Clip clip = scene::LoadClip(dir / "clip");
  const scene::Clip truth = scene::LoadClip(dir / "synth");
  ASSERT_EQ(clip.frame_count(), synth.frames);
  ASSERT_EQ(recording->times_s.size(), std::size_t(synth.frames));
  const auto homogeneous = [](const Eigen::Matrix<double, 3, 4>& pose) {
    Eigen::Matrix4d m = Eigen::Matrix4d::Identity();
    m.topRows<3>() = pose;
    return m;
  };
  const Eigen::Matrix4d first = homogeneous(truth.cameras[0].c2w).inverse();
  const Eigen::Matrix4d estimated_first = homogeneous(clip.cameras[0].c2w).inverse();
  // As PoseEstimatorTest holds the estimator: 5% of the path's length, half a degree.
  double length = 0, worst_miss = 0;
  Eigen::Vector3d previous = Eigen::Vector3d::Zero();
  for (int f = 1; f < synth.frames; ++f) {
    const Eigen::Matrix4d exact = first * homogeneous(truth.cameras[f].c2w);
    const Eigen::Matrix4d estimate = estimated_first * homogeneous(clip.cameras[f].c2w);
    length += (exact.topRightCorner<3, 1>() - previous).norm();
    previous = exact.topRightCorner<3, 1>();
    worst_miss =
        std::max(worst_miss, (estimate.topRightCorner<3, 1>() - exact.topRightCorner<3, 1>()).norm());
    const Eigen::Matrix3d difference =
        estimate.topLeftCorner<3, 3>().transpose() * exact.topLeftCorner<3, 3>();
    EXPECT_LT(Eigen::AngleAxisd(difference).angle() * 180 / M_PI, 0.5) << "frame " << f;
  }
  EXPECT_GT(length, 3) << "the synthetic endoscope should move";
  EXPECT_LT(worst_miss, 0.05 * length);

  options.endoscope = dicom::Endoscope::kFixed;
  ASSERT_TRUE(ClipFromRecording(dir / "sbs.dcm", options, dir / "fixed").has_value());
  const scene::Clip fixed = scene::LoadClip(dir / "fixed");
  for (int f = 1; f < synth.frames; ++f) EXPECT_EQ(fixed.cameras[f].c2w, fixed.cameras[0].c2w);
}

// Where the first frame's pixel (u, v) lands in frame f, on a surface far away (a turn moves every
// pixel alike at any depth), as the loaded clip's cameras say.
cv::Point2d SeenIn(const scene::Clip& clip, int f, double u, double v) {
  Eigen::Vector3d origin, direction;
  clip.cameras[0].Ray(u - 0.5, v - 0.5, origin, direction);
  double x = 0, y = 0;
  EXPECT_TRUE(clip.cameras[f].ToPixel(origin + 1e4 * direction, x, y));
  return {x, y};
}

TEST(RecordingClipTest, MonoRecordingOfATurningEndoscopeGetsTurningCameras) {
  testing::TempDir dir("recording-clip-mono");
  const auto scope = testing::MakeTurningCamera({320, 180}, {{0, 2, 0}, {1, 4, 1}, {2, 5, 4}});
  const std::vector<double> times = {0, 0.2, 0.4, 0.6};
  dicom::RecordingHeader header;
  header.study = dicom::NewStudyContext("P-1", "Doe^Jane", "", "");
  dicom::WriteEndoscopicFrames(scope.frames, times, false, header, dir / "mono.dcm");

  const auto turning = ClipFromRecording(dir / "mono.dcm", dicom::RecordingOptions{}, dir / "turning");
  ASSERT_TRUE(turning.has_value());
  const scene::Clip clip = scene::LoadClip(dir / "turning");
  ASSERT_EQ(clip.frame_count(), 4);
  const cv::Matx33d k = scope.camera;
  for (int f = 1; f < 4; ++f) {
    for (const cv::Point2d at : {cv::Point2d(160, 90), cv::Point2d(100, 60), cv::Point2d(220, 130)}) {
      // The truth: the ray of pixel `at` in the first camera, in camera f.
      const cv::Vec3d ray = scope.turns[f].t() * (k.inv() * cv::Vec3d(at.x, at.y, 1));
      const cv::Point2d truth(k(0, 0) * ray[0] / ray[2] + k(0, 2), k(1, 1) * ray[1] / ray[2] + k(1, 2));
      EXPECT_LT(cv::norm(SeenIn(clip, f, at.x, at.y) - truth), 0.3) << "frame " << f << " at " << at;
    }
  }
  std::ifstream record_file(dir / "turning/recording.json");
  const auto record = nlohmann::json::parse(record_file);
  EXPECT_EQ(record.at("endoscope"), "moving");
  EXPECT_NEAR(record.at("camera_turns").at("widest_deg").get<double>(), cv::norm(cv::Vec3d(2, 5, 4)), 0.1);
  EXPECT_EQ(record.at("camera_turns").at("frames_unplaced"), 0);

  dicom::RecordingOptions still;
  still.endoscope = dicom::Endoscope::kFixed;
  ASSERT_TRUE(ClipFromRecording(dir / "mono.dcm", still, dir / "fixed").has_value());
  const scene::Clip fixed = scene::LoadClip(dir / "fixed");
  for (int f = 1; f < 4; ++f) EXPECT_EQ(fixed.cameras[f].c2w, fixed.cameras[0].c2w);
}

TEST(RecordingClipTest, ARecordingIsScaledToTheSizeAskedWhenItKeepsItsShape) {
  testing::TempDir dir("recording-clip-size");
  const auto scope = testing::MakeTurningCamera({320, 180}, {{0, 2, 0}, {1, 4, 1}});
  dicom::RecordingHeader header;
  header.study = dicom::NewStudyContext("P-1", "Doe^Jane", "", "");
  dicom::WriteEndoscopicFrames(scope.frames, {0, 0.2, 0.4}, false, header, dir / "mono.dcm");

  dicom::RecordingOptions options;
  options.size = cv::Size(160, 90);
  const auto recording = ClipFromRecording(dir / "mono.dcm", options, dir / "small");
  ASSERT_TRUE(recording.has_value());
  EXPECT_NE(recording->summary.find("scaled to 160x90"), std::string::npos) << recording->summary;
  const scene::Clip clip = scene::LoadClip(dir / "small");
  EXPECT_EQ(clip.width, 160);
  EXPECT_EQ(clip.height, 90);
  EXPECT_NEAR(clip.cameras[0].fx, 0.8898 * 160, 1e-9);
  cv::Mat expected;
  cv::resize(scope.frames[1], expected, {160, 90}, 0, 0, cv::INTER_AREA);
  const cv::Mat written = cv::imread((dir / "small/images" / eval::FrameFileName(1, ".png")).string());
  EXPECT_EQ(cv::norm(written, expected, cv::NORM_INF), 0);
  // The turns are the same at either size, to a few hundredths of a degree.
  const auto full = ClipFromRecording(dir / "mono.dcm", dicom::RecordingOptions{}, dir / "full");
  const scene::Clip whole = scene::LoadClip(dir / "full");
  const Eigen::Matrix3d difference =
      clip.cameras[2].c2w.leftCols<3>().transpose() * whole.cameras[2].c2w.leftCols<3>();
  EXPECT_LT(Eigen::AngleAxisd(difference).angle() * 180 / M_PI, 0.05);

  options.size = cv::Size(160, 120);
  try {
    ClipFromRecording(dir / "mono.dcm", options, dir / "squashed");
    ADD_FAILURE() << "a size of another shape was accepted";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("size 160x120 changes the recording's 320x180 aspect ratio; give a "
                                         "size of the same shape, e.g. 160x90"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace endorecon::worker
