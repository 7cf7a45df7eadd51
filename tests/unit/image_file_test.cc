// Untrusted image bytes: a header that declares a frame too large to decode is said to be one (as
// the clips' size limit is), not passed on as OpenCV's assertion text.
#include "worker/engine/scene/image_file.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::scene {
namespace {

// PNG chunks carry a CRC-32 (ISO 3309) of their type and data; a changed IHDR needs its CRC anew, or
// libpng refuses the chunk before it looks at the size. Bitwise: a test needs no table.
std::uint32_t Crc32(const std::string& bytes) {
  std::uint32_t crc = 0xFFFFFFFFu;
  for (const unsigned char byte : bytes) {
    crc ^= byte;
    for (int bit = 0; bit < 8; ++bit) crc = (crc >> 1) ^ (0xEDB88320u & (0u - (crc & 1u)));
  }
  return ~crc;
}

void PutBigEndian(std::string& bytes, std::size_t at, std::uint32_t value) {
  for (int k = 0; k < 4; ++k) bytes[at + k] = char((value >> (24 - 8 * k)) & 0xFF);
}

TEST(ImageFileTest, AHeaderDeclaringTooManyPixelsIsSaidToBeTooLarge) {
  testing::TempDir dir("image-file");
  std::vector<unsigned char> png;
  ASSERT_TRUE(cv::imencode(".png", cv::Mat(4, 4, CV_8UC3, cv::Scalar(10, 20, 30)), png));
  std::string bytes(png.begin(), png.end());
  // The IHDR chunk: length at 8, type at 12, width at 16, height at 20, CRC at 29 (over 12..28).
  ASSERT_EQ(bytes.substr(12, 4), "IHDR");
  PutBigEndian(bytes, 16, 100000);
  PutBigEndian(bytes, 20, 100000);
  PutBigEndian(bytes, 29, Crc32(bytes.substr(12, 17)));
  testing::WriteBytes(dir / "big.png", bytes);
  const std::string message =
      testing::ErrorFrom([&] { DecodeImageFile(dir / "big.png"); }, ErrorCode::kInvalidArgument);
  EXPECT_NE(message.find("big.png: the image's header declares more pixels than can be decoded"),
            std::string::npos)
      << message;
  // The same bytes with the true size decode.
  PutBigEndian(bytes, 16, 4);
  PutBigEndian(bytes, 20, 4);
  PutBigEndian(bytes, 29, Crc32(bytes.substr(12, 17)));
  testing::WriteBytes(dir / "small.png", bytes);
  EXPECT_EQ(DecodeImageFile(dir / "small.png").cols, 4);
}

}  // namespace
}  // namespace endorecon::scene
