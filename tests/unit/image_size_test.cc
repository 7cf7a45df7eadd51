// ImageSizeOf (common/image_bytes.h) against the files real encoders write: the CLI compares a clip's
// frames by it before an upload.
#include <gtest/gtest.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "common/image_bytes.h"
#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {

TEST(ImageSizeTest, PngJpegAndBmpHeadersGiveTheirSizeAndTiffIsLeftOut) {
  testing::TempDir dir("image-size");
  const cv::Mat colour(48, 64, CV_8UC3, cv::Scalar(10, 120, 200));
  const cv::Mat depth(48, 64, CV_16UC1, cv::Scalar(1000));
  for (const char* name : {"a.png", "a.jpg", "a.bmp", "d.png"}) {
    ASSERT_TRUE(cv::imwrite((dir / name).string(), name[0] == 'd' ? depth : colour)) << name;
    const auto size = ImageSizeOf(dir / name);
    ASSERT_TRUE(size) << name;
    EXPECT_EQ(size->width, 64) << name;
    EXPECT_EQ(size->height, 48) << name;
  }
  // A progressive JPEG's frame header (SOF2).
  ASSERT_TRUE(cv::imwrite((dir / "p.jpg").string(), colour, {cv::IMWRITE_JPEG_PROGRESSIVE, 1}));
  EXPECT_EQ(ImageSizeOf(dir / "p.jpg")->width, 64);
  ASSERT_TRUE(cv::imwrite((dir / "a.tif").string(), colour));
  EXPECT_FALSE(ImageSizeOf(dir / "a.tif"));
  testing::WriteBytes(dir / "text.png", "not an image");
  EXPECT_FALSE(ImageSizeOf(dir / "text.png"));
}

}  // namespace
}  // namespace endorecon
