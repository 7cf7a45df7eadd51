#include "common/output_folder.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;

void Check(const fs::path& out, const fs::path& input) { CheckOutputFolder(out, input, "the clip's folder"); }

TEST(OutputFolderTest, TheInputsOwnFolderIsRefusedUnderAnyName) {
  testing::TempDir dir("output-folder");
  fs::create_directories(dir / "clip" / "images");
  fs::create_directory_symlink(dir / "clip", dir / "link");
  for (const fs::path& out : {dir / "clip", dir / "clip" / "images" / "..", dir / "link"}) {
    const std::string message = testing::ErrorFrom([&] { Check(out, dir / "clip"); });
    EXPECT_NE(message.find("is the clip's folder"), std::string::npos) << out << ": " << message;
    EXPECT_NE(message.find("choose another output folder"), std::string::npos) << message;
  }
}

TEST(OutputFolderTest, AnotherFolderOrOneNotYetMadeIsFine) {
  testing::TempDir dir("output-folder");
  fs::create_directories(dir / "clip");
  fs::create_directories(dir / "results");
  EXPECT_NO_THROW(Check(dir / "results", dir / "clip"));
  EXPECT_NO_THROW(Check(dir / "clip" / "results", dir / "clip")) << "a folder inside the clip's is its own";
  EXPECT_NO_THROW(Check(dir / "new", dir / "clip"));
  EXPECT_NO_THROW(Check(dir / "results", dir / "recording.dcm"))
      << "a recording file is no folder to overwrite";
}

}  // namespace
}  // namespace endorecon
