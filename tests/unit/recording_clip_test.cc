// A DICOM recording turned into the engine's clip: a side-by-side stereo recording of the synthetic
// scene gets a depth prior by stereo matching, close to the generator's own depth (the synthetic
// scene has the nominal focal length and baseline a recording is assumed to have).
#include "worker/runtime/recording_clip.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <vector>

#include "common/dicom/recording_writer.h"
#include "common/dicom/uid.h"
#include "tests/unit/temp_dir.h"
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

}  // namespace
}  // namespace endorecon::worker
