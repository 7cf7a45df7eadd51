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

// Another clip, or a file, is no output folder either: `render -o CLIP` wrote its depth maps over the
// clip's and the clip no longer loaded; `-o FILE` failed with a bare filesystem error (found
// 2026-12-05).
TEST(OutputFolderTest, AnotherClipOrAFileIsRefused) {
  testing::TempDir dir("output-folder");
  fs::create_directories(dir / "results");
  fs::create_directories(dir / "other");
  testing::WriteBytes(dir / "other" / "poses_bounds.npy", "rows");
  std::string message = testing::ErrorFrom([&] { Check(dir / "other", dir / "results"); });
  EXPECT_NE(message.find("other holds a clip"), std::string::npos) << message;
  testing::WriteBytes(dir / "afile", "x");
  message = testing::ErrorFrom([&] { Check(dir / "afile", dir / "results"); });
  EXPECT_NE(message.find("afile is a file"), std::string::npos) << message;
}

// A non-empty folder holding no earlier results is someone's files: refused (`-o ~/Documents` mixed
// the results into them until 2026-12-05). An earlier run's results, or only dot files, are written
// over.
TEST(OutputFolderTest, SomeonesFilesAreRefusedAndEarlierResultsAreNot) {
  testing::TempDir dir("output-folder");
  fs::create_directories(dir / "clip");
  fs::create_directories(dir / "documents");
  testing::WriteBytes(dir / "documents" / ".DS_Store", "x");
  EXPECT_NO_THROW(Check(dir / "documents", dir / "clip")) << "dot files do not count";
  testing::WriteBytes(dir / "documents" / "letter.txt", "x");
  const std::string message = testing::ErrorFrom([&] { Check(dir / "documents", dir / "clip"); });
  EXPECT_NE(message.find("documents holds other files (letter.txt, ...) and no earlier results"),
            std::string::npos)
      << message;
  fs::create_directories(dir / "results" / "clip");
  EXPECT_NO_THROW(Check(dir / "results", dir / "results" / "clip"))
      << "the input inside the output folder (a worker's prepared clip) is no one else's file";
  for (const char* earlier : {"config.json", "metrics.json", "render.json", "cameras.json"}) {
    testing::TempDir run("output-folder");
    fs::create_directories(run / "clip");
    fs::create_directories(run / "out" / "rgb");
    testing::WriteBytes(run / "out" / earlier, "{}");
    EXPECT_NO_THROW(Check(run / "out", run / "clip")) << earlier;
  }
}

}  // namespace
}  // namespace endorecon
