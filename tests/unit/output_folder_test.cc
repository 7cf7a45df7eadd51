#include "common/output_folder.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "common/error.h"
#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;

std::string ErrorOf(const fs::path& out, const fs::path& input) {
  try {
    CheckOutputFolder(out, input, "the clip's folder");
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    return e.what();
  }
  return "";
}

TEST(OutputFolderTest, TheInputsOwnFolderIsRefusedUnderAnyName) {
  testing::TempDir dir("output-folder");
  fs::create_directories(dir / "clip" / "images");
  fs::create_directory_symlink(dir / "clip", dir / "link");
  for (const fs::path& out : {dir / "clip", dir / "clip" / "images" / "..", dir / "link"}) {
    const std::string message = ErrorOf(out, dir / "clip");
    EXPECT_NE(message.find("is the clip's folder"), std::string::npos) << out << ": " << message;
    EXPECT_NE(message.find("choose another output folder"), std::string::npos) << message;
  }
}

TEST(OutputFolderTest, AnotherFolderOrOneNotYetMadeIsFine) {
  testing::TempDir dir("output-folder");
  fs::create_directories(dir / "clip");
  fs::create_directories(dir / "results");
  EXPECT_EQ(ErrorOf(dir / "results", dir / "clip"), "");
  EXPECT_EQ(ErrorOf(dir / "clip" / "results", dir / "clip"), "") << "a folder inside the clip's is its own";
  EXPECT_EQ(ErrorOf(dir / "new", dir / "clip"), "");
  EXPECT_EQ(ErrorOf(dir / "results", dir / "recording.dcm"), "") << "a recording file is no folder to overwrite";
}

}  // namespace
}  // namespace endorecon
