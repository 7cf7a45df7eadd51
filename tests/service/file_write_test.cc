#include "common/file_write.h"

#include <gtest/gtest.h>

#include <fstream>
#include <iterator>

#include "common/error.h"
#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {

TEST(FileWrite, WritesTheWholeFileAndLeavesNoTemporary) {
  testing::TempDir dir("file-write");
  const auto path = dir / "a" / "b" / "metrics.json";
  WriteFile(path, "{\"x\": 1}", "metrics");
  std::ifstream in(path);
  EXPECT_EQ(std::string(std::istreambuf_iterator<char>(in), {}), "{\"x\": 1}");
  EXPECT_FALSE(std::filesystem::exists(path.string() + ".tmp"));
}

TEST(FileWrite, AFailureNamesWhatAndWhere) {
  testing::TempDir dir("file-write");
  // A parent that is a file: neither the folder nor the file can be made.
  std::ofstream(dir / "blocker") << "x";
  const auto path = dir / "blocker" / "metrics.json";
  try {
    WriteFile(path, "{}", "metrics");
    FAIL() << "wrote under a file";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kUnavailable);
    EXPECT_NE(std::string(e.what()).find("cannot write metrics " + path.string()), std::string::npos)
        << e.what();
  }
}

TEST(FileWrite, AFullDiskIsResourceExhausted) {
  if (!std::filesystem::exists("/dev/full")) GTEST_SKIP() << "no /dev/full on this machine";
  // /dev/full takes the open but fails every write with ENOSPC; the rename then never happens.
  testing::TempDir dir("file-write");
  const auto path = dir / "out.bin";
  std::filesystem::create_symlink("/dev/full", path.string() + ".tmp");
  try {
    WriteFile(path, std::string(1 << 16, 'x'), "result");
    FAIL() << "wrote to a full disk";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kResourceExhausted) << e.what();
    EXPECT_NE(std::string(e.what()).find(path.string()), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace endorecon
