#include "worker/engine/eval/video_writer.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>
#include <vector>

#include "common/error.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::eval {
namespace {

using testing::TempDir;

TEST(VideoWriter, Mp4ReadsBackWithEveryFrame) {
  TempDir dir("video");
  constexpr int kW = 64, kH = 48, kFrames = 9;
  std::vector<std::vector<float>> frames(kFrames);
  for (int f = 0; f < kFrames; ++f) {
    frames[f].resize(kW * kH * 3);
    for (int p = 0; p < kW * kH; ++p) {
      frames[f][3 * p + 0] = 0.8f;  // flat reddish frames, so colours survive compression
      frames[f][3 * p + 1] = 0.2f;
      frames[f][3 * p + 2] = 0.1f + 0.05f * f;
    }
  }
  VideoWriter writer(dir / "video.mp4", kW, kH, 10.0);
  for (const auto& frame : frames) writer.Write(frame);
  writer.Close();
  EXPECT_EQ(writer.path(), dir / "video.mp4") << "fell back to " << writer.codec();
  EXPECT_EQ(writer.frames_written(), kFrames);
  ASSERT_TRUE(std::filesystem::exists(writer.path()));
  EXPECT_GT(std::filesystem::file_size(writer.path()), 0u);

  cv::VideoCapture capture(writer.path().string());
  ASSERT_TRUE(capture.isOpened());
  int read = 0;
  cv::Mat frame;
  while (capture.read(frame)) {
    ASSERT_EQ(frame.cols, kW);
    ASSERT_EQ(frame.rows, kH);
    const cv::Scalar mean = cv::mean(frame);  // BGR
    EXPECT_NEAR(mean[2], 0.8 * 255, 12);
    EXPECT_NEAR(mean[1], 0.2 * 255, 12);
    EXPECT_NEAR(mean[0], (0.1 + 0.05 * read) * 255, 12);
    ++read;
  }
  EXPECT_EQ(read, kFrames);
}

TEST(VideoWriter, RejectsBadSizesAndWritesAfterClose) {
  TempDir dir("video");
  EXPECT_THROW(VideoWriter(dir / "a.mp4", 0, 10, 10.0), Error);
  VideoWriter writer(dir / "b.mp4", 16, 16, 5.0);
  EXPECT_THROW(writer.Write(std::vector<float>(10)), Error);
  writer.Write(std::vector<float>(16 * 16 * 3, 0.5f));
  writer.Close();
  EXPECT_EQ(writer.frames_written(), 1);
  EXPECT_THROW(writer.Write(std::vector<float>(16 * 16 * 3, 0.5f)), Error);
}

}  // namespace
}  // namespace endorecon::eval
