#include "common/image_bytes.h"

#include <gtest/gtest.h>
#include <zlib.h>

#include <cstdint>
#include <string>

#include "common/error.h"
#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {

using testing::TempDir;
using testing::WriteBytes;

std::string BigEndian(std::uint32_t n) {
  return {static_cast<char>(n >> 24), static_cast<char>(n >> 16), static_cast<char>(n >> 8),
          static_cast<char>(n)};
}

// A chunk: length (big-endian), type, data, CRC (of type and data).
std::string Chunk(const std::string& type, const std::string& data) {
  const std::string crc_input = type + data;
  const auto crc =
      crc32(0L, reinterpret_cast<const Bytef*>(crc_input.data()), static_cast<uInt>(crc_input.size()));
  return BigEndian(static_cast<std::uint32_t>(data.size())) + crc_input +
         BigEndian(static_cast<std::uint32_t>(crc));
}

const std::string kSignature("\x89PNG\r\n\x1a\n", 8);

std::string WholePng() {
  return kSignature + Chunk("IHDR", std::string(13, '\1')) + Chunk("IDAT", std::string(300, 'x')) +
         Chunk("IDAT", std::string(200, 'y')) + Chunk("IEND", "");
}

// The message of the error CheckImageBytes throws for `bytes` (empty when it throws none).
std::string Refusal(const TempDir& dir, const std::string& bytes) {
  WriteBytes(dir / "frame.png", bytes);
  try {
    CheckImageBytes(dir / "frame.png");
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find((dir / "frame.png").string()), std::string::npos) << e.what();
    return e.what();
  }
  return "";
}

TEST(ImageBytesTest, AWholePngPassesAndBytesAfterItsEndAreAllowed) {
  TempDir dir;
  EXPECT_EQ(Refusal(dir, WholePng()), "");
  EXPECT_EQ(Refusal(dir, WholePng() + "trailing bytes some tools append"), "");
}

TEST(ImageBytesTest, APngCutAnywhereIsTruncatedAndSaysWhere) {
  TempDir dir;
  const std::string png = WholePng();
  // Inside the second IDAT: its chunk starts at 8 + 25 + 312 = 345 and needs 212 bytes.
  std::string message = Refusal(dir, png.substr(0, 400));
  EXPECT_NE(message.find("a truncated PNG: its chunk IDAT at byte 345 needs 557 bytes, the file has 400"),
            std::string::npos)
      << message;
  // Between chunks, before IEND (every chunk whole).
  message = Refusal(dir, png.substr(0, png.size() - 12));
  EXPECT_NE(message.find("a truncated PNG: it ends at byte 557 before its IEND chunk"), std::string::npos)
      << message;
  // The signature alone; one byte short of the end.
  EXPECT_NE(Refusal(dir, kSignature).find("a truncated PNG"), std::string::npos);
  EXPECT_NE(Refusal(dir, png.substr(0, png.size() - 1)).find("a truncated PNG: its chunk IEND"),
            std::string::npos);
}

TEST(ImageBytesTest, AChunkLongerThanPngAllowsIsDamaged) {
  TempDir dir;
  const std::string message = Refusal(dir, kSignature + std::string("\xff\xff\xff\xff", 4) + "IDAT");
  EXPECT_NE(message.find("a damaged PNG: its chunk IDAT at byte 8 declares 4294967295 bytes"),
            std::string::npos)
      << message;
}

TEST(ImageBytesTest, OtherFormatsAreToldByTheirFirstBytes) {
  TempDir dir;
  for (const std::string& magic : {std::string("\xff\xd8\xff\xe0", 4), std::string("BM"),
                                   std::string("II*\0", 4), std::string("MM\0*", 4)}) {
    EXPECT_EQ(Refusal(dir, magic + "rest of the file"), "") << magic;
  }
  EXPECT_NE(Refusal(dir, "not an image at all").find("not a PNG, JPEG, BMP or TIFF image"),
            std::string::npos);
  EXPECT_NE(Refusal(dir, "").find("an empty file (0 bytes)"), std::string::npos);
}

// A damaged byte was reported by the decoder only as "cannot decode the image" (libpng's CRC error
// went to stderr; found 2026-12-05).
TEST(ImageBytesTest, AChunkFailingItsCrcIsDamage) {
  TempDir dir;
  std::string png = WholePng();
  png[8 + 25 + 8 + 100] ^= 0x01;  // a bit of the first IDAT's data
  const std::string message = Refusal(dir, png);
  EXPECT_NE(message.find("a damaged PNG: its chunk IDAT at byte 33 fails its CRC check"), std::string::npos)
      << message;
}

// A PNG zero-padded after an interrupted, preallocated copy was walked in 12-byte steps to its end
// (2 GB: minutes; found 2026-12-05): bytes that are no chunk type stop the walk.
TEST(ImageBytesTest, ZerosWhereAChunkShouldBeginAreDamage) {
  TempDir dir;
  const std::string png = WholePng();
  const std::string message = Refusal(dir, png.substr(0, 345) + std::string(4096, '\0'));
  EXPECT_NE(message.find("a damaged PNG: at byte 345, where a chunk should begin, its type is 0x00000000"),
            std::string::npos)
      << message;
}

// A JPEG cut short decoded with a warning on stderr and grey below the cut (found 2026-12-05).
TEST(ImageBytesTest, AJpegWithoutItsEndOfImageIsTruncated) {
  TempDir dir;
  // SOI; an APP1 holding a thumbnail's own EOI; SOS (length 8); entropy-coded data with a stuffed FF.
  const std::string head = std::string("\xff\xd8", 2) + std::string("\xff\xe1\x00\x06\xff\xd9\x00\x00", 8) +
                           std::string("\xff\xda\x00\x08", 4) + std::string(6, '\1') + "abc" +
                           std::string("\xff\x00", 2) + "def";
  EXPECT_EQ(Refusal(dir, head + std::string("\xff\xd9", 2)), "");
  EXPECT_EQ(Refusal(dir, head + std::string("\xff\xd9", 2) + "trailing"), "");
  const std::string message = Refusal(dir, head);
  EXPECT_NE(message.find("a truncated JPEG: no end-of-image marker after its scan, which starts at byte 10"),
            std::string::npos)
      << message;
}

TEST(ImageBytesTest, AMissingFileIsNamed) {
  TempDir dir;
  try {
    CheckImageBytes(dir / "absent.png");
    ADD_FAILURE() << "accepted a missing file";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("absent.png: file does not exist"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace endorecon
