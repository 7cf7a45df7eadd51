#include "worker/engine/scene/clip_loader.h"

#include <gtest/gtest.h>

#include <fstream>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon::scene {
namespace {

namespace fs = std::filesystem;
using testing::ErrorFrom;
using testing::Pattern;
using testing::TempDir;
using testing::WriteImage;

void WriteEndoNerfClip(const fs::path& dir, int frames) {
  for (int i = 0; i < frames; ++i) {
    WriteImage(dir / "images" / (std::to_string(i) + ".png"),
               Pattern(8, 6, CV_8UC3, [](int x, int) { return x; }));
  }
  testing::WritePoses(dir / "poses_bounds.npy", std::vector<testing::PoseRow>(frames));
}

TEST(ClipLoaderTest, MissingFolderIsNotFound) {
  TempDir dir("clip");
  const std::string message = ErrorFrom([&] { LoadClip(dir / "absent"); }, ErrorCode::kNotFound);
  EXPECT_NE(message.find("absent: clip folder does not exist"), std::string::npos) << message;
}

// A video given where a clip is expected (reconstruct reads DICOM recordings, not video files).
TEST(ClipLoaderTest, AFileSaysWhatAClipIsAndHowAVideoBecomesOne) {
  TempDir dir("clip");
  std::ofstream(dir / "endo.mp4") << "not a clip";
  const std::string message = ErrorFrom([&] { LoadClip(dir / "endo.mp4"); });
  EXPECT_NE(message.find("endo.mp4: a file, not a clip"), std::string::npos) << message;
  EXPECT_NE(message.find("to-dicom"), std::string::npos) << message;
}

TEST(ClipLoaderTest, FolderWithoutLayoutSaysWhatWasLookedFor) {
  TempDir dir("clip");
  const std::string message = ErrorFrom([&] { LoadClip(dir.path()); });
  EXPECT_NE(message.find("neither transforms.json"), std::string::npos) << message;
  EXPECT_NE(message.find("nor poses_bounds.npy"), std::string::npos) << message;
}

TEST(ClipLoaderTest, PrefersTransformsJson) {
  TempDir dir("clip");
  WriteEndoNerfClip(dir.path(), 2);
  testing::WriteBytes(dir / "transforms.json", R"({"fl_x": 5, "near": 1, "far": 2, "frames": [
    {"file_path": "images/0.png", "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})");
  EXPECT_EQ(LoadClip(dir.path()).frame_count(), 1);
  fs::remove(dir / "transforms.json");
  EXPECT_EQ(LoadClip(dir.path()).frame_count(), 2);
}

TEST(ClipLoaderTest, LoadsGroundTruthFolder) {
  TempDir dir("clip");
  WriteEndoNerfClip(dir.path(), 2);
  const std::vector<float> depth(48, 7.5f);
  fs::create_directories(dir / "gt/depth");
  for (int i = 0; i < 2; ++i) {
    WriteImage(dir / "gt/images" / (std::to_string(i) + ".png"),
               Pattern(8, 6, CV_8UC3, [i](int, int) { return 40 + i; }));
    WriteNpyFloat32(dir / "gt/depth" / (std::to_string(i) + ".npy"), depth.data(), {6, 8});
  }
  const Clip clip = LoadClip(dir.path());
  ASSERT_EQ(clip.gt_rgb.size(), 2u);
  EXPECT_EQ(clip.gt_rgb[1][2], 41);
  ASSERT_EQ(clip.gt_depth.size(), 2u);
  EXPECT_EQ(clip.gt_depth[0][47], 7.5f);

  fs::remove(dir / "gt/depth/1.npy");
  const std::string message = ErrorFrom([&] { LoadClip(dir.path()); });
  EXPECT_NE(message.find("gt/depth: holds 1 files but the clip has 2 frames"), std::string::npos) << message;
}

// --frames picks a clip folder's frames, as if the clip had been cut to them by hand: a long clip
// was cut by slicing poses_bounds.npy or transforms.json (found 2026-12-06). An EndoNeRF clip's times
// spread over the picked frames, a transforms.json clip's own times stay; gt/ is picked alike.
TEST(ClipLoaderTest, FramesPicksTheClipFoldersFramesAsIfCutByHand) {
  TempDir dir("clip");
  std::vector<testing::PoseRow> rows(8);
  for (int i = 0; i < 8; ++i) {
    rows[i].t[0] = i;  // each frame's camera told apart by its position
    WriteImage(dir / "images" / (std::to_string(i) + ".png"),
               Pattern(8, 6, CV_8UC3, [i](int, int) { return 10 * i; }));
    WriteImage(dir / "gt/images" / (std::to_string(i) + ".png"),
               Pattern(8, 6, CV_8UC3, [i](int, int) { return 100 + i; }));
  }
  testing::WritePoses(dir / "poses_bounds.npy", rows);
  LoadOptions options;
  options.frames = ParseFrameRange("2:8:2");
  const Clip clip = LoadClip(dir.path(), options);
  ASSERT_EQ(clip.frame_count(), 3);
  EXPECT_EQ(clip.rgb[1][2], 40);  // frame 4 (blue: Pattern fills the first of BGR)
  EXPECT_EQ(clip.cameras[2].c2w(0, 3), 6.0);
  EXPECT_EQ(clip.times, (std::vector<float>{0.f, 0.5f, 1.f}));
  ASSERT_EQ(clip.gt_rgb.size(), 3u);
  EXPECT_EQ(clip.gt_rgb[2][2], 106);

  options.frames = ParseFrameRange("8:");
  const std::string none = ErrorFrom([&] { LoadClip(dir.path(), options); });
  EXPECT_NE(none.find(dir.path().string() + ": --frames 8::1 picks none of the clip's 8 frames"),
            std::string::npos)
      << none;

  testing::WriteBytes(dir / "transforms.json", R"({"fl_x": 5, "near": 1, "far": 2, "frames": [
    {"file_path": "images/0.png", "time": 0.0, "transform_matrix": [[1,0,0,0],[0,1,0,0],[0,0,1,0],[0,0,0,1]]},
    {"file_path": "images/1.png", "time": 0.1, "transform_matrix": [[1,0,0,1],[0,1,0,0],[0,0,1,0],[0,0,0,1]]},
    {"file_path": "images/2.png", "time": 0.2, "transform_matrix": [[1,0,0,2],[0,1,0,0],[0,0,1,0],[0,0,0,1]]},
    {"file_path": "images/3.png", "time": 1.0, "transform_matrix": [[1,0,0,3],[0,1,0,0],[0,0,1,0],[0,0,0,1]]}]})");
  fs::remove_all(dir / "gt");
  options.frames = ParseFrameRange("1:3");
  const Clip picked = LoadClip(dir.path(), options);
  ASSERT_EQ(picked.frame_count(), 2);
  EXPECT_EQ(picked.rgb[0][2], 10);
  EXPECT_EQ(picked.cameras[1].c2w(0, 3), 2.0);
  EXPECT_FLOAT_EQ(picked.times[0], 0.1f);
  EXPECT_FLOAT_EQ(picked.times[1], 0.2f);
}

// A clip whose decoded frames and the run's per-pixel state exceed the memory given is refused before a
// frame is decoded (a damaged frame is not reached), naming the need, what is there and how many frames fit;
// a ground-truth folder counts its colour and depth too.
TEST(ClipLoaderTest, AClipTooLargeForMemoryIsRefusedBeforeDecoding) {
  TempDir dir("clip");
  WriteEndoNerfClip(dir.path(), 10);  // 8x6 frames, colour only: 3 bytes a pixel
  LoadOptions options;
  options.run_bytes_per_pixel = 6;          // 9 bytes a pixel, 432 a frame, 4,320 the clip
  options.run_bytes_per_depth_pixel = 100;  // the clip has no depth
  options.memory_bytes = 4320;
  EXPECT_EQ(LoadClip(dir.path(), options).frame_count(), 10);

  testing::WriteBytes(dir / "images/1.png", "not a png");
  options.memory_bytes = 2000;
  const std::string message =
      ErrorFrom([&] { LoadClip(dir.path(), options); }, ErrorCode::kResourceExhausted);
  EXPECT_NE(message.find(dir.path().string() + ": 10 frames of 8x6 need about 0.0 GiB of memory"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("about 4 frames of this size fit"), std::string::npos) << message;
  EXPECT_NE(message.find("--frames START:END:STEP"), std::string::npos) << message;

  WriteEndoNerfClip(dir.path(), 10);
  fs::create_directories(dir / "gt/images");
  for (int i = 0; i < 10; ++i) {
    WriteImage(dir / "gt/images" / (std::to_string(i) + ".png"),
               Pattern(8, 6, CV_8UC3, [](int, int) { return 9; }));
  }
  options.memory_bytes = 4320;  // 16 bytes a pixel with the ground truth's colour and depth: 7,680
  ErrorFrom([&] { LoadClip(dir.path(), options); }, ErrorCode::kResourceExhausted);
  options.memory_bytes = 7680;
  EXPECT_EQ(LoadClip(dir.path(), options).gt_rgb.size(), 10u);

  // Depth priors: 4 bytes a pixel decoded, and the run's state for them (100 here) beside.
  const std::vector<float> depth(48, 1.5f);
  fs::create_directories(dir / "depth");
  for (int i = 0; i < 10; ++i)
    WriteNpyFloat32(dir / "depth" / (std::to_string(i) + ".npy"), depth.data(), {6, 8});
  ErrorFrom([&] { LoadClip(dir.path(), options); }, ErrorCode::kResourceExhausted);
  options.memory_bytes = 10 * 48 * (3 + 7 + 4 + 6 + 100);
  EXPECT_EQ(LoadClip(dir.path(), options).depth.size(), 10u);
}

}  // namespace
}  // namespace endorecon::scene
