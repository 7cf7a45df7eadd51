#include "worker/engine/eval/exports.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/npy.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::eval {
namespace {

using testing::TempDir;

TEST(Exports, FrameFileNamesAreSixDigits) {
  EXPECT_EQ(FrameFileName(12, ".png"), "000012.png");
  EXPECT_EQ(FrameFileName(1234567, ".npy"), "1234567.npy");
  EXPECT_THROW(FrameFileName(-1, ".png"), Error);
}

TEST(Exports, Png8ClampsAndRoundsInRgbOrder) {
  TempDir dir("exports");
  const std::vector<float> rgb = {1.0f, 0.5f, 0.0f, -0.2f, 1.7f, std::nanf(""), 0.2f, 0.4f, 0.6f,
                                  0.0f, 0.0f, 1.0f, 0.1f,  0.1f, 0.1f,          0.9f, 0.9f, 0.9f};
  WritePng8(dir / "a.png", rgb, 3, 2);
  const cv::Mat back = cv::imread((dir / "a.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(back.type(), CV_8UC3);
  ASSERT_EQ(back.cols, 3);
  ASSERT_EQ(back.rows, 2);
  EXPECT_EQ(back.at<cv::Vec3b>(0, 0), cv::Vec3b(0, 128, 255));  // BGR of (1, 0.5, 0)
  EXPECT_EQ(back.at<cv::Vec3b>(0, 1), cv::Vec3b(0, 255, 0));    // clamped, NaN as 0
  EXPECT_EQ(back.at<cv::Vec3b>(1, 0), cv::Vec3b(255, 0, 0));
  EXPECT_THROW(WritePng8(dir / "b.png", rgb, 2, 2), Error);
}

TEST(Exports, Png8ToAMissingFolderIsUnavailable) {
  TempDir dir("exports");
  try {
    WritePng8(dir / "missing" / "a.png", std::vector<float>(3, 0.5f), 1, 1);
    FAIL() << "expected an error";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kUnavailable);
    EXPECT_NE(std::string(e.what()).find("missing"), std::string::npos);
  }
}

TEST(Exports, DepthPng16RoundTripsWithinHalfAStep) {
  TempDir dir("exports");
  const double far = 7.5, scale = DepthPngScale(far);
  EXPECT_DOUBLE_EQ(scale, 65535.0 / 7.5);
  const std::vector<float> depth = {0.0f, 1.234f, 7.5f, 9.0f, -1.0f, std::numeric_limits<float>::infinity()};
  WriteDepthPng16(dir / "d.png", depth, 3, 2, scale);
  const cv::Mat back = cv::imread((dir / "d.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(back.type(), CV_16UC1);
  EXPECT_EQ(back.at<std::uint16_t>(0, 0), 0);
  EXPECT_NEAR(back.at<std::uint16_t>(0, 1) / scale, 1.234, 0.5 / scale + 1e-6);
  EXPECT_EQ(back.at<std::uint16_t>(0, 2), 65535);  // far fits exactly
  EXPECT_EQ(back.at<std::uint16_t>(1, 0), 65535);  // beyond far saturates
  EXPECT_EQ(back.at<std::uint16_t>(1, 1), 0);
  EXPECT_EQ(back.at<std::uint16_t>(1, 2), 0);
  EXPECT_THROW(DepthPngScale(0.0), Error);
}

TEST(Exports, DepthNpyHasHeightByWidthShape) {
  TempDir dir("exports");
  const std::vector<float> depth = {1, 2, 3, 4, 5, 6};
  WriteDepthNpy(dir / "d.npy", depth, 3, 2);
  const NpyArray back = ReadNpy(dir / "d.npy");
  EXPECT_EQ(back.dtype, "<f4");
  EXPECT_EQ(back.shape, (std::vector<std::size_t>{2, 3}));
  EXPECT_EQ(back.data[5], 6.0);
}

TEST(Exports, PlyIsBinaryLittleEndianWithColours) {
  TempDir dir("exports");
  PointCloud cloud;
  cloud.xyz = {1.5f, -2.0f, 3.25f, 0.0f, 0.5f, -7.0f};
  cloud.rgb = {255, 0, 10, 1, 2, 3};
  WritePly(dir / "p.ply", cloud);
  const std::string bytes = testing::ReadBytes(dir / "p.ply");
  const std::string end = "end_header\n";
  const std::size_t body = bytes.find(end) + end.size();
  const std::string header = bytes.substr(0, body);
  EXPECT_EQ(header.rfind("ply\nformat binary_little_endian 1.0\n", 0), 0u);
  EXPECT_NE(header.find("element vertex 2\n"), std::string::npos);
  EXPECT_NE(header.find("property float x\nproperty float y\nproperty float z\n"), std::string::npos);
  EXPECT_NE(header.find("property uchar red\nproperty uchar green\nproperty uchar blue\n"),
            std::string::npos);
  ASSERT_EQ(bytes.size(), body + 2 * 15);
  float xyz[3];
  std::memcpy(xyz, bytes.data() + body + 15, sizeof xyz);
  EXPECT_EQ(xyz[0], 0.0f);
  EXPECT_EQ(xyz[2], -7.0f);
  EXPECT_EQ(static_cast<std::uint8_t>(bytes[body + 12]), 255);
  EXPECT_EQ(static_cast<std::uint8_t>(bytes[body + 15 + 14]), 3);

  cloud.rgb.pop_back();
  EXPECT_THROW(WritePly(dir / "q.ply", cloud), Error);
}

TEST(Exports, HeatmapUsesOneFixedScale) {
  TempDir dir("exports");
  const std::vector<float> values = {0.0f, 0.5f, 1.0f, 2.0f, std::nanf(""), -1.0f};
  WriteHeatmapPng(dir / "h.png", values, 3, 2, 0.0, 1.0);
  const cv::Mat back = cv::imread((dir / "h.png").string(), cv::IMREAD_UNCHANGED);
  ASSERT_EQ(back.type(), CV_8UC3);
  const cv::Vec3b low = back.at<cv::Vec3b>(0, 0), high = back.at<cv::Vec3b>(0, 2);
  EXPECT_LT(low[0] + low[1] + low[2], 30);    // inferno starts near black
  EXPECT_GT(high[1] + high[2], 400);          // and ends pale yellow
  EXPECT_EQ(back.at<cv::Vec3b>(1, 0), high);  // clamped above vmax
  EXPECT_EQ(back.at<cv::Vec3b>(1, 2), low);   // clamped below vmin
  EXPECT_EQ(back.at<cv::Vec3b>(1, 1), cv::Vec3b(128, 128, 128));
  EXPECT_THROW(WriteHeatmapPng(dir / "x.png", values, 3, 2, 1.0, 1.0), Error);
}

TEST(Exports, HeatmapUpperBoundIsAClipQuantile) {
  std::vector<std::vector<float>> frames(2);
  for (int i = 1; i <= 100; ++i) frames[i % 2].push_back(static_cast<float>(i));
  frames[0].push_back(std::nanf(""));
  EXPECT_EQ(HeatmapUpperBound(frames, 0.99), 99.0f);
  EXPECT_EQ(HeatmapUpperBound(frames, 1.0), 100.0f);
  const std::vector<std::vector<float>> zeros = {std::vector<float>(10, 0.0f)};
  EXPECT_EQ(HeatmapUpperBound(zeros), 1.0);
}

// Gathered frame by frame: every value up to its cap (the same bound as the whole clip's), and past
// it every k-th value, its stride running on across frames, within a percent of the whole's.
TEST(Exports, AHeatmapScaleGatheredFrameByFrameKeepsToTheClipsBound) {
  std::vector<std::vector<float>> frames(30, std::vector<float>(997));
  std::uint64_t state = 7;
  for (auto& frame : frames) {
    for (float& v : frame) {
      state = state * 6364136223846793005ULL + 1442695040888963407ULL;
      v = float(std::exp(double(state >> 11) / double(1ULL << 53) * 4));  // 1 to e^4, skewed
    }
  }
  HeatmapScale every(30 * 997);
  HeatmapScale sampled(30 * 997, 2000);
  for (const auto& frame : frames) {
    every.Add(frame);
    sampled.Add(frame);
  }
  EXPECT_EQ(every.stride(), 1u);
  EXPECT_EQ(every.UpperBound(), HeatmapUpperBound(frames));
  EXPECT_EQ(sampled.stride(), 15u);  // 29,910 values, at most 2,000 kept
  EXPECT_NEAR(sampled.UpperBound(), HeatmapUpperBound(frames), 0.01 * HeatmapUpperBound(frames));
  EXPECT_NE(sampled.UpperBound(), HeatmapUpperBound(frames)) << "a sample, not every value";
}

// A view past the scene rendered depth = far everywhere (the far plane composited into transparent
// rays), which the depth files and the report's surface showed as a wall (found 2026-12-05).
TEST(Exports, DepthWithoutASurfaceIsNoDepth) {
  std::vector<float> depth = {2.0f, 130.0f, 90.0f, 50.0f};
  const std::vector<float> opacity = {1.0f, 0.0f, 0.49f, 0.5f};
  ClearDepthWithoutSurface(depth, opacity);
  EXPECT_EQ(depth, (std::vector<float>{2.0f, 0.0f, 0.0f, 50.0f}));
  std::vector<float> nan_opacity = {1.0f};
  nan_opacity[0] = std::nanf("");
  std::vector<float> one = {3.0f};
  ClearDepthWithoutSurface(one, nan_opacity);
  EXPECT_EQ(one[0], 0.0f) << "no opacity, no surface";
  EXPECT_THROW(ClearDepthWithoutSurface(depth, nan_opacity), Error);
}

// A tool's pixels (5% of a frame, its error ten times the tissue's) set the error maps' bound and left
// the tissue near black (found 2026-12-05): with the tool mask they are left out of the scale.
TEST(Exports, AHeatmapScaleLeavesTheToolOut) {
  std::vector<float> frame(100, 0.1f);
  std::vector<std::uint8_t> tool(100, 0);
  for (int i = 0; i < 5; ++i) {
    frame[i] = 1.0f;
    tool[i] = 255;
  }
  frame[50] = 0.2f;
  HeatmapScale with_tool(100), tissue(100);
  with_tool.Add(frame);
  tissue.Add(frame, tool);
  EXPECT_FLOAT_EQ(float(with_tool.UpperBound()), 1.0f);
  EXPECT_FLOAT_EQ(float(tissue.UpperBound()), 0.2f) << "the 99th percentile of the 95 tissue pixels";
  EXPECT_THROW(tissue.Add(frame, std::vector<std::uint8_t>(99, 0)), Error);
}

}  // namespace
}  // namespace endorecon::eval
