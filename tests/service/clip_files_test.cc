#include "common/clip_files.h"

#include <gtest/gtest.h>

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/npy.h"
#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;
using testing::TempDir;
using testing::WriteBytes;

std::string ErrorOf(const std::function<void()>& call) {
  try {
    call();
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    return e.what();
  }
  ADD_FAILURE() << "no error";
  return "";
}

// An EndoNeRF-layout folder of `rows` frames: poses, images/ and masks/ (files named 000000.png ...;
// their bytes are not looked at here).
void MakeEndoNerfFolder(const fs::path& dir, std::size_t rows, std::size_t columns = kPoseColumns) {
  const std::vector<double> poses(rows * columns, 1.0);
  WriteNpyFloat64(dir / "poses_bounds.npy", poses.data(), {rows, columns});
  for (const char* folder : {"images", "masks"}) {
    fs::create_directories(dir / folder);
    for (std::size_t i = 0; i < rows; ++i) {
      char name[16];
      std::snprintf(name, sizeof(name), "%06zu.png", i);
      WriteBytes(dir / folder / name, "bytes");
    }
  }
}

TEST(ClipFilesTest, AnEndoNerfFolderPairsItsFilesByTheirSortedOrder) {
  TempDir dir;
  MakeEndoNerfFolder(dir.path(), 3);
  WriteBytes(dir / "images" / ".hidden.png", "skipped");
  WriteBytes(dir / "images" / "notes.txt", "skipped");
  EXPECT_EQ(FindClipLayout(dir.path()), ClipLayout::kEndoNerf);
  const std::vector<FrameFiles> frames = ListClipFrames(dir.path());
  ASSERT_EQ(frames.size(), 3u);
  EXPECT_EQ(frames[2].image, dir / "images" / "000002.png");
  EXPECT_EQ(frames[2].tool_mask, dir / "masks" / "000002.png");
  EXPECT_TRUE(frames[2].depth.empty());
  EXPECT_TRUE(frames[2].right_image.empty());
}

// FFmpeg's `%d.png` names frames 0.png ... 15.png: string order put 10-15 before 2 and scrambled
// time without a word (found 2026-12-05). Numbers in names are compared as numbers.
TEST(ClipFilesTest, FramesNamedWithoutPaddingKeepTheirNumbersOrder) {
  testing::TempDir dir("clip-files");
  std::filesystem::create_directories(dir / "images");
  for (const char* name : {"10.png", "2.png", "0.png", "1.png", "frame9.png", "frame10.png", "01.png"})
    testing::WriteBytes(dir / "images" / name, "x");
  std::vector<std::string> names;
  for (const auto& file : ListFiles(dir / "images", ImageExtensions())) names.push_back(file.filename().string());
  EXPECT_EQ(names, (std::vector<std::string>{"0.png", "01.png", "1.png", "2.png", "10.png", "frame9.png",
                                             "frame10.png"}));
  EXPECT_TRUE(NaturalLess("000009.png", "000010.png"));
  EXPECT_FALSE(NaturalLess("000010.png", "000009.png"));
  EXPECT_TRUE(NaturalLess("a.png", "b.png"));
  EXPECT_TRUE(NaturalLess("img", "img1"));
  EXPECT_FALSE(NaturalLess("x.png", "x.png"));
  EXPECT_TRUE(NaturalLess("99999999999999999999999.png", "100000000000000000000000.png"))
      << "numbers longer than any integer";
}

// A missing image is named too (it said only the counts): by the gap in numbered names, else by
// another per-frame folder with a file for every row.
TEST(ClipFilesTest, AMissingImageIsNamed) {
  TempDir dir;
  MakeEndoNerfFolder(dir.path(), 4);
  fs::remove(dir / "images" / "000002.png");
  std::string message = ErrorOf([&] { ListClipFrames(dir.path()); });
  EXPECT_NE(message.find("images: holds 3 files but poses_bounds.npy has 4 rows"), std::string::npos)
      << message;
  EXPECT_NE(message.find("; no 000002.* between 000001 and 000003"), std::string::npos) << message;
  fs::rename(dir / "images" / "000003.png", dir / "images" / "c.png");
  fs::rename(dir / "masks" / "000003.png", dir / "masks" / "c.png");
  message = ErrorOf([&] { ListClipFrames(dir.path()); });
  EXPECT_NE(message.find("; no file named 000002.* for masks/000002.png"), std::string::npos) << message;
  // The last one missing leaves no gap: said from the masks.
  fs::rename(dir / "images" / "c.png", dir / "images" / "000002.png");
  fs::remove(dir / "masks" / "c.png");
  WriteBytes(dir / "masks" / "000003.png", "bytes");
  message = ErrorOf([&] { ListClipFrames(dir.path()); });
  EXPECT_NE(message.find("; no file named 000003.* for masks/000003.png"), std::string::npos) << message;
}

TEST(ClipFilesTest, AMissingMaskNamesTheFrameThatLacksIt) {
  TempDir dir;
  MakeEndoNerfFolder(dir.path(), 3);
  fs::remove(dir / "masks" / "000001.png");
  const std::string message = ErrorOf([&] { ListClipFrames(dir.path()); });
  EXPECT_NE(message.find("masks: holds 2 files but poses_bounds.npy has 3 rows"), std::string::npos)
      << message;
  EXPECT_NE(message.find("no file named 000001.* for images/000001.png"), std::string::npos) << message;
}

TEST(ClipFilesTest, APoseFileOfAnotherShapeOrNoFolderIsRefused) {
  TempDir dir;
  MakeEndoNerfFolder(dir.path(), 3, 15);
  std::string message = ErrorOf([&] { ListClipFrames(dir.path()); });
  EXPECT_NE(message.find("poses_bounds.npy: expected an array of shape (N, 17), found (3, 15)"),
            std::string::npos)
      << message;
  TempDir empty;
  message = ErrorOf([&] { ListClipFrames(empty.path()); });
  EXPECT_NE(message.find(": not a clip: found neither transforms.json"), std::string::npos) << message;
  EXPECT_FALSE(FindClipLayout(empty.path()));
}

TEST(ClipFilesTest, ATransformsFileResolvesItsPathsInsideTheClipOnly) {
  TempDir dir;
  fs::create_directories(dir / "images");
  WriteBytes(dir / "images" / "a.png", "bytes");
  WriteBytes(dir / "transforms.json", R"({"frames": [{"file_path": "images/a"}]})");
  EXPECT_EQ(FindClipLayout(dir.path()), ClipLayout::kTransforms);
  const std::vector<FrameFiles> frames = ListClipFrames(dir.path());
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_EQ(frames[0].image, dir / "images" / "a.png");

  WriteBytes(dir / "transforms.json",
             R"({"frames": [{"file_path": "images/a"}, {"file_path": "../../etc/passwd"}]})");
  std::string message = ErrorOf([&] { ListClipFrames(dir.path()); });
  EXPECT_NE(message.find("transforms.json frame 1: file_path \"../../etc/passwd\" leaves the clip's folder"),
            std::string::npos)
      << message;
  WriteBytes(dir / "transforms.json", R"({"frames": [{"file_path": "images/b"}]})");
  message = ErrorOf([&] { ListClipFrames(dir.path()); });
  EXPECT_NE(message.find("images/b does not exist (also tried adding .png, .jpg, .jpeg, .npy)"),
            std::string::npos)
      << message;
  // One image for two frames (found 2026-12-05: 3,000 frames of one PNG decoded into gigabytes).
  WriteBytes(dir / "transforms.json",
             R"({"frames": [{"file_path": "images/a"}, {"file_path": "./images/a.png"}]})");
  message = ErrorOf([&] { ListClipFrames(dir.path()); });
  EXPECT_NE(message.find("transforms.json frame 1: its file_path " + (dir / "images" / "a.png").string() +
                         " is frame 0's too"),
            std::string::npos)
      << message;
  WriteBytes(dir / "transforms.json", R"({"frames": [1, 2]})");
  message = ErrorOf([&] { ListClipFrames(dir.path()); });
  EXPECT_NE(message.find("transforms.json frame 0: not an object"), std::string::npos) << message;
}

// What the CLI uploads of a clip folder: the files a loader reads, in either layout, and nothing else
// (a spreadsheet of patients beside the frames went up with them until 2026-12-06).
TEST(ClipFilesTest, AClipsFilesAreTheOnesItsLayoutNames) {
  TempDir dir;
  MakeEndoNerfFolder(dir.path(), 2);
  WriteBytes(dir / "stereo.json", R"({"baseline": 5})");
  WriteBytes(dir / "patients.csv", "MRN,name");
  WriteBytes(dir / "images" / "notes.txt", "not a frame");
  for (const char* folder : {"gt/images", "gt/depth"}) fs::create_directories(dir / folder);
  for (const char* name : {"000000", "000001"}) {
    WriteBytes(dir / "gt" / "images" / (std::string(name) + ".png"), "truth");
    WriteBytes(dir / "gt" / "depth" / (std::string(name) + ".npy"), "depth");
  }
  std::vector<fs::path> expected{dir / "poses_bounds.npy",
                                 dir / "stereo.json",
                                 dir / "images" / "000000.png",
                                 dir / "masks" / "000000.png",
                                 dir / "images" / "000001.png",
                                 dir / "masks" / "000001.png",
                                 dir / "gt" / "images" / "000000.png",
                                 dir / "gt" / "depth" / "000000.npy",
                                 dir / "gt" / "images" / "000001.png",
                                 dir / "gt" / "depth" / "000001.npy"};
  EXPECT_EQ(ListClipFiles(dir.path()), expected);
  // The ground truth's count is the clip's, as the loader holds it.
  fs::remove(dir / "gt" / "depth" / "000001.npy");
  const std::string message = ErrorOf([&] { ListClipFiles(dir.path()); });
  EXPECT_NE(message.find("gt/depth: holds 1 files but the clip has 2 frames"), std::string::npos) << message;

  TempDir transforms;
  fs::create_directories(transforms / "images");
  WriteBytes(transforms / "images" / "a.png", "bytes");
  WriteBytes(transforms / "images" / "unused.png", "bytes");
  WriteBytes(transforms / "depth.npy", "bytes");
  WriteBytes(transforms / "images" / "b.png", "bytes");
  WriteBytes(transforms / "mask.png", "bytes");
  // Frames may share a mask (a tool that stays put): listed once, as a manifest must.
  WriteBytes(
      transforms / "transforms.json",
      R"({"frames": [{"file_path": "images/a", "depth_file_path": "depth.npy", "mask_path": "mask.png"},
                            {"file_path": "images/b.png", "mask_path": "./mask.png"}]})");
  EXPECT_EQ(ListClipFiles(transforms.path()),
            (std::vector<fs::path>{transforms / "transforms.json", transforms / "images" / "a.png",
                                   transforms / "depth.npy", transforms / "mask.png",
                                   transforms / "images" / "b.png"}));
}

}  // namespace
}  // namespace endorecon
