#include "common/output_folder.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;

void Check(const fs::path& out, const fs::path& input) {
  CheckOutputFolder(out, input, "the clip's folder", ResultsKind::kReconstruction);
}

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
  for (const char* earlier : {"config.json", "metrics.json"}) {
    testing::TempDir run("output-folder");
    fs::create_directories(run / "clip");
    fs::create_directories(run / "out" / "rgb");
    testing::WriteBytes(run / "out" / earlier, "{}");
    EXPECT_NO_THROW(Check(run / "out", run / "clip")) << earlier;
  }
}

// A render into a reconstruction's results overwrote its report and first frames and left the rest; a
// folder of the user's own cameras.json was taken for a render's (found 2026-12-05).
TEST(OutputFolderTest, TheOtherKindsResultsAreRefused) {
  testing::TempDir dir("output-folder");
  fs::create_directories(dir / "results");
  testing::WriteBytes(dir / "results" / "config.json", "{}");
  fs::create_directories(dir / "views");
  testing::WriteBytes(dir / "views" / "render.json", "{}");
  fs::create_directories(dir / "mine");
  testing::WriteBytes(dir / "mine" / "cameras.json", "{}");
  const auto render_into = [&](const fs::path& out) {
    return testing::ErrorFrom(
        [&] { CheckOutputFolder(out, dir / "model", "the results folder", ResultsKind::kRender); });
  };
  EXPECT_NE(
      render_into(dir / "results").find("holds a reconstruction's results, which a render's views would"),
      std::string::npos)
      << render_into(dir / "results");
  EXPECT_NE(render_into(dir / "mine").find("holds other files (cameras.json, ...)"), std::string::npos)
      << render_into(dir / "mine");
  EXPECT_NO_THROW(
      CheckOutputFolder(dir / "views", dir / "model", "the results folder", ResultsKind::kRender));
  const std::string message = testing::ErrorFrom([&] { Check(dir / "views", dir / "clip"); });
  EXPECT_NE(message.find("holds a render's views"), std::string::npos) << message;
}

// A rerun without uncertainty kept the earlier run's maps, and a dicom/ that described another model;
// a render of fewer views kept the earlier views' frames (found 2026-12-05).
TEST(OutputFolderTest, AnEarlierRunsResultsAreClearedButWhatARunReads) {
  testing::TempDir dir("output-folder");
  const fs::path out = dir / "out";
  for (const char* sub : {"rgb", "uncertainty", "dicom", "model", "clip"}) fs::create_directories(out / sub);
  for (const char* file :
       {"config.json", "metrics.json", "report.html", "rgb/000009.png", "uncertainty/000000.npy",
        "dicom/rgb.dcm", "model/checkpoint.bin", "clip/poses_bounds.npy", "notes.txt"}) {
    testing::WriteBytes(out / file, "x");
  }
  fs::create_directories(dir / "elsewhere");
  testing::WriteBytes(dir / "elsewhere" / "frame.png", "x");
  fs::create_directory_symlink(dir / "elsewhere", out / "error");
  ClearEarlierResults(out, ResultsKind::kReconstruction, {out / "clip", out / "model" / "checkpoint.bin"});
  for (const char* gone : {"metrics.json", "report.html", "rgb", "uncertainty", "dicom", "error"}) {
    EXPECT_FALSE(fs::exists(fs::symlink_status(out / gone))) << gone;
  }
  for (const char* kept : {"config.json", "model/checkpoint.bin", "clip/poses_bounds.npy", "notes.txt"}) {
    EXPECT_TRUE(fs::exists(out / kept)) << kept;
  }
  EXPECT_TRUE(fs::exists(dir / "elsewhere" / "frame.png")) << "a link is removed, not what it points to";
  // What a run reads is kept even where a run writes: the cameras a render was given as OUT/cameras.json.
  testing::WriteBytes(out / "cameras.json", "{}");
  testing::WriteBytes(out / "render.json", "{}");
  ClearEarlierResults(out, ResultsKind::kRender, {out / "cameras.json"});
  EXPECT_TRUE(fs::exists(out / "cameras.json"));
  EXPECT_TRUE(fs::exists(out / "render.json"));
  ClearEarlierResults(out, ResultsKind::kRender, {});
  EXPECT_FALSE(fs::exists(out / "cameras.json"));
}

}  // namespace
}  // namespace endorecon
