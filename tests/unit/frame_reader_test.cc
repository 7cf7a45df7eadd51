// What the clip loaders decode: only the image formats they accept reach OpenCV.
#include "worker/engine/scene/frame_reader.h"

#include <gtest/gtest.h>

#include <opencv2/imgcodecs.hpp>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::scene {
namespace {

// Found by tests/fuzz/image_decode_fuzz.cc: OpenCV chooses a decoder by content, and a broken DICOM
// file named .png reached GDCM, which aborted the process. It is refused before any decoder runs.
TEST(FrameReaderTest, AFileOfAnotherFormatIsRefusedBeforeDecoding) {
  testing::TempDir dir("frames");
  std::string dicom(128, '\0');
  dicom += "DICM";
  dicom += std::string(64, '\x01');
  testing::WriteBytes(dir.path() / "frame.png", dicom);
  const std::string message = testing::ErrorFrom([&] { ReadRgbImage(dir.path() / "frame.png"); });
  EXPECT_NE(message.find("frame.png: not a PNG, JPEG, BMP or TIFF image"), std::string::npos) << message;

  cv::imwrite((dir.path() / "real.png").string(), cv::Mat(3, 4, CV_8UC3, cv::Scalar(1, 2, 3)));
  const RgbImage image = ReadRgbImage(dir.path() / "real.png");
  EXPECT_EQ(image.width, 4);
  EXPECT_EQ(image.height, 3);
}

// Found by tests/fuzz/image_decode_fuzz.cc: a BMP whose header declares a width of 4,194,308 made
// OpenCV throw cv::Exception (its size limit), which escaped as no endorecon error.
TEST(FrameReaderTest, AnImageDeclaringASizeOverOpenCvsLimitIsRefused) {
  testing::TempDir dir("frames");
  const std::string bmp(
      "\x42\x4d\x5a\x00\x00\x00\x00\x00\x00\x00\x36\x00\x00\x00\x28\x00\x00\x00\x04\x00"
      "\x40\x00\x03\x00\x00\x00\x01\x00\x18\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00"
      "\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x0a\x14\x1e\x0a\x14\x1e"
      "\x0a\x14\x1e\x0a\x14\x1e\x0a\x14\x1e\x0a\x14\x1e\x0a\x14\x1f\x0a\x14\x1e\x0a\x14"
      "\x1e\x0a\x14\x1e\x0a\x14\x1e\x0a\x14\x1e",
      90);
  testing::WriteBytes(dir.path() / "wide.bmp", bmp);
  const std::string message = testing::ErrorFrom([&] { ReadRgbImage(dir.path() / "wide.bmp"); });
  EXPECT_NE(message.find("wide.bmp: cannot decode the image"), std::string::npos) << message;
}

// Object captures store the background as transparency (NeRF-synthetic): RGBA is composited onto
// the background it is read with, straight alpha, rounded.
TEST(FrameReaderTest, RgbaImagesAreCompositedOntoTheBackground) {
  testing::TempDir dir("frames");
  cv::Mat bgra(1, 3, CV_8UC4);
  bgra.at<cv::Vec4b>(0, 0) = {10, 20, 200, 255};  // opaque red-ish
  bgra.at<cv::Vec4b>(0, 1) = {0, 0, 0, 0};        // transparent
  bgra.at<cv::Vec4b>(0, 2) = {0, 100, 200, 51};   // a fifth opaque
  cv::imwrite((dir.path() / "object.png").string(), bgra);
  const RgbImage white = ReadRgbImage(dir.path() / "object.png");
  EXPECT_TRUE(white.transparent);
  EXPECT_EQ(white.rgb, (std::vector<std::uint8_t>{200, 20, 10, 255, 255, 255, 244, 224, 204}));
  const RgbImage black = ReadRgbImage(dir.path() / "object.png", {0, 0, 0});
  EXPECT_EQ(black.rgb, (std::vector<std::uint8_t>{200, 20, 10, 0, 0, 0, 40, 20, 0}));

  cv::Mat opaque(2, 2, CV_8UC4, cv::Scalar(1, 2, 3, 255));
  cv::imwrite((dir.path() / "opaque.png").string(), opaque);
  EXPECT_FALSE(ReadRgbImage(dir.path() / "opaque.png").transparent);
}

}  // namespace
}  // namespace endorecon::scene
