// What real frames make different, on the real laparoscopic video (monocular, so its right eye is
// made here: the frame shifted by 16 pixels, a known disparity): H.264 decoding, the black corners
// outside the scope's round view (excluded as screen regions), real highlights (no depth) and
// real tissue texture (the known depth where matching succeeds).
#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>
#include <opencv2/videoio.hpp>

#include "tests/unit/synthetic_recording_fixture.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/prepare/frame_source.h"
#include "worker/prepare/specular_mask.h"

namespace endorecon::testing {
namespace {

namespace fs = std::filesystem;

constexpr int kShift = 16;

TEST(RealRecordingTest, KnownDisparityOnRealLaparoscopicFrames) {
  const fs::path video = fs::path(ENDORECON_SHARED_DIR) / "data/real/laparoscopy_mono/endo.mp4";
  if (!fs::exists(video)) GTEST_SKIP() << "the real video is not here: " << video;
  TempDir dir("real-recording");
  auto source = prepare::OpenFrameSource(video);
  cv::VideoWriter both((dir / "sbs.avi").string(), cv::CAP_OPENCV_MJPEG,
                       cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), 25, cv::Size(1280, 360));
  prepare::SourceFrame frame;
  for (int i = 0; i < 4 && source->Next(frame); ++i) {
    cv::Mat left, right(360, 640, CV_8UC3, cv::Scalar::all(0)), pair;
    cv::resize(frame.image, left, cv::Size(640, 360), 0, 0, cv::INTER_AREA);
    left(cv::Rect(kShift, 0, 640 - kShift, 360)).copyTo(right(cv::Rect(0, 0, 640 - kShift, 360)));
    cv::hconcat(left, right, pair);
    both.write(pair);
  }
  both.release();

  prepare::PrepareOptions options;
  options.recording = {prepare::StereoLayout::kSideBySide, {}, {}, dir / "sbs.avi"};
  options.rectified = true;
  options.focal = 500;
  options.baseline = 5;
  // The black sides of the round view, in each eye's half of the stored frames.
  options.exclude = {ParsePixelRect("0,0,70,360"), ParsePixelRect("570,0,70,360"),
                     ParsePixelRect("640,0,70,360"), ParsePixelRect("1210,0,70,360")};
  options.out = dir / "clip";
  const prepare::PrepareSummary summary = prepare::PrepareClip(options);
  EXPECT_EQ(summary.frames, 4);
  const scene::Clip clip = scene::LoadClip(dir / "clip");
  ASSERT_TRUE(clip.has_masks());
  const double expected = 500.0 * 5 / kShift;
  std::size_t valid = 0, close = 0, kept = 0, highlights = 0, highlight_depth = 0;
  for (int f = 0; f < clip.frame_count(); ++f) {
    cv::Mat bgr(clip.height, clip.width, CV_8UC3);
    for (int p = 0; p < clip.width * clip.height; ++p) {
      bgr.at<cv::Vec3b>(p / clip.width, p % clip.width) =
          cv::Vec3b(clip.rgb[f][3 * p + 2], clip.rgb[f][3 * p + 1], clip.rgb[f][3 * p]);
    }
    const cv::Mat specular = prepare::SpecularMask(bgr, 200, 0);
    for (int p = 0; p < clip.width * clip.height; ++p) {
      const int x = p % clip.width;
      const float z = clip.depth[f][p];
      if (x < 70 || x >= 570) {
        EXPECT_EQ(clip.tool_mask[f][p], 1) << "excluded";
        EXPECT_EQ(z, 0.f) << "excluded";
        continue;
      }
      ++kept;
      if (specular.at<std::uint8_t>(p / clip.width, x)) {
        ++highlights;
        highlight_depth += z > 0;
      }
      if (z <= 0) continue;
      ++valid;
      close += std::abs(z - expected) < 0.02 * expected;
    }
  }
  EXPECT_GT(highlights, 0u) << "real frames have highlights";
  EXPECT_EQ(highlight_depth, 0u) << "no depth on a highlight";
  EXPECT_GT(valid, kept * 6 / 10) << "real texture matches";
  EXPECT_GT(close, valid * 95 / 100) << "at the known depth " << expected;
}

}  // namespace
}  // namespace endorecon::testing
