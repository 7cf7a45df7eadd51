#include "common/file_download.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;

v1::FileRange Range(const std::string& path, const std::string& sha256) {
  v1::FileRange range;
  range.set_path(path);
  range.set_sha256(sha256);
  return range;
}

std::string Read(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// A content under several names (the identical masks of frames without a tool, copied frames) is
// asked for once and copied to its other names, replacing what stood there and its .part (3,000 hard
// links of one frame were downloaded 3,000 times; found 2026-12-06).
TEST(FileDownloadTest, AContentUnderSeveralNamesIsAskedForOnceAndCopied) {
  const std::string a(64, 'a'), b(64, 'b');
  const std::vector<v1::FileRange> pending = {Range("masks/0.png", a), Range("images/0.png", b),
                                              Range("masks/1.png", a), Range("masks/2.png", a)};
  const auto asked = OnePerContent(pending);
  ASSERT_EQ(asked.size(), 2u);
  EXPECT_EQ(asked[0].path(), "masks/0.png");
  EXPECT_EQ(asked[1].path(), "images/0.png");

  testing::TempDir dir("download");
  fs::create_directories(dir / "masks");
  fs::create_directories(dir / "images");
  std::ofstream(dir / "masks/0.png") << "mask";
  std::ofstream(dir / "images/0.png") << "image";
  std::ofstream(dir / "masks/1.png") << "MASK";       // another content of the same size: replaced
  std::ofstream(dir / "masks/2.png.part") << "ma";    // an earlier download's part: removed
  CopyDuplicates(dir.path(), pending);
  EXPECT_EQ(Read(dir / "masks/1.png"), "mask");
  EXPECT_EQ(Read(dir / "masks/2.png"), "mask");
  EXPECT_FALSE(fs::exists(dir / "masks/2.png.part"));
  EXPECT_EQ(Read(dir / "images/0.png"), "image");
}

}  // namespace
}  // namespace endorecon
