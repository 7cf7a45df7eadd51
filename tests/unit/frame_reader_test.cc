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

}  // namespace
}  // namespace endorecon::scene
