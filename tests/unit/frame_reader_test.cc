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

}  // namespace
}  // namespace endorecon::scene
