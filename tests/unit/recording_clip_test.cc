// A DICOM recording turned into the engine's clip: a side-by-side stereo recording of the synthetic
// scene gets a depth prior by stereo matching, close to the generator's own depth (the synthetic
// scene has the nominal focal length and baseline a recording is assumed to have); a mono recording
// of a turning endoscope gets cameras that turn as it did, or one still camera when asked.
#include "worker/runtime/recording_clip.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "common/dicom/recording_writer.h"
#include "common/dicom/uid.h"
#include "tests/unit/temp_dir.h"
#include "tests/unit/turning_camera_frames.h"
#include "worker/engine/eval/exports.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/synthetic_clip.h"

namespace endorecon::worker {
namespace {

TEST(RecordingClipTest, SideBySideRecordingGetsADepthPriorFromStereo) {
  testing::TempDir dir("recording-clip");
  scene::SynthOptions synth;
  synth.frames = 4;
  synth.width = 160;
  synth.height = 128;
  synth.stereo = true;
  scene::WriteSyntheticClip(synth, dir / "synth");

  std::vector<cv::Mat> frames;
  std::vector<double> times;
  for (int f = 0; f < synth.frames; ++f) {
    const std::string name = eval::FrameFileName(f, ".png");
    const cv::Mat left = cv::imread((dir / "synth/images" / name).string());
    const cv::Mat right = cv::imread((dir / "synth/images_right" / name).string());
    ASSERT_FALSE(left.empty() || right.empty()) << name;
    cv::Mat both;
    cv::hconcat(left, right, both);
    frames.push_back(both);
    times.push_back(0.04 * f);
  }
  dicom::RecordingHeader header;
  header.study = dicom::NewStudyContext("P-1", "Doe^Jane", "", "");
  dicom::WriteEndoscopicFrames(frames, times, false, header, dir / "sbs.dcm");

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
  EXPECT_EQ(record.at("mono_camera"), "turning");
  EXPECT_NEAR(record.at("camera_turns").at("widest_deg").get<double>(), cv::norm(cv::Vec3d(2, 5, 4)), 0.1);
  EXPECT_EQ(record.at("camera_turns").at("frames_unplaced"), 0);

  dicom::RecordingOptions still;
  still.mono_camera = dicom::MonoCamera::kFixed;
  ASSERT_TRUE(ClipFromRecording(dir / "mono.dcm", still, dir / "fixed").has_value());
  const scene::Clip fixed = scene::LoadClip(dir / "fixed");
  for (int f = 1; f < 4; ++f) EXPECT_EQ(fixed.cameras[f].c2w, fixed.cameras[0].c2w);
}

}  // namespace
}  // namespace endorecon::worker
