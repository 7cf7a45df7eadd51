// What an upload lists: every regular file under the clip's folder, through linked folders; an entry
// that is no file (a broken link, a pipe) is named instead of left out of the upload.
#include "common/manifest.h"

#include <gtest/gtest.h>
#include <sys/stat.h>

#include <filesystem>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;

std::string ErrorOf(const fs::path& dir) {
  return testing::ErrorFrom([&] { ManifestOfDirectory(dir); });
}

TEST(ManifestTest, ListsFilesThroughLinkedFolders) {
  testing::TempDir dir("manifest");
  fs::create_directories(dir / "clip");
  fs::create_directories(dir / "elsewhere");
  testing::WriteBytes(dir / "clip" / "poses_bounds.npy", "p");
  testing::WriteBytes(dir / "elsewhere" / "000000.png", "i");
  fs::create_directory_symlink(dir / "elsewhere", dir / "clip" / "images");
  const v1::Manifest manifest = ManifestOfDirectory(dir / "clip");
  ASSERT_EQ(manifest.files_size(), 2);
  EXPECT_EQ(manifest.files(0).path(), "images/000000.png");
  EXPECT_EQ(manifest.files(1).path(), "poses_bounds.npy");
}

TEST(ManifestTest, AnEntryThatIsNoFileIsNamed) {
  testing::TempDir dir("manifest");
  fs::create_directories(dir / "clip");
  testing::WriteBytes(dir / "clip" / "poses_bounds.npy", "p");
  fs::create_symlink(dir / "nowhere.png", dir / "clip" / "000001.png");
  std::string message = ErrorOf(dir / "clip");
  EXPECT_NE(message.find("000001.png: not a regular file"), std::string::npos) << message;
  fs::remove(dir / "clip" / "000001.png");
  ASSERT_EQ(::mkfifo((dir / "clip" / "000002.png").c_str(), 0600), 0);
  message = ErrorOf(dir / "clip");
  EXPECT_NE(message.find("000002.png: not a regular file"), std::string::npos) << message;
  fs::remove(dir / "clip" / "000002.png");
  // A folder linked into itself, or below itself, is named once, not as loop/loop/loop/... up to
  // the system's limit on links.
  fs::create_directories(dir / "clip" / "images");
  fs::create_directory_symlink("..", dir / "clip" / "images" / "up");
  message = ErrorOf(dir / "clip");
  EXPECT_NE(message.find("clip/images/up (a link to ..): leads back to a folder it is in"), std::string::npos)
      << message;
  EXPECT_EQ(message.find("up/images"), std::string::npos) << message;
  // The same folder linked twice side by side is no loop: its files are listed under both names.
  fs::remove(dir / "clip" / "images" / "up");
  testing::WriteBytes(dir / "clip" / "images" / "000000.png", "i");
  fs::create_directory_symlink(dir / "clip" / "images", dir / "clip" / "masks");
  EXPECT_EQ(ManifestOfDirectory(dir / "clip").files_size(), 3);
}

// Sizes whose sum passed the largest int64 wrapped to a negative total, under the upload limit,
// the free-space check and the tenant's quota.
TEST(ManifestTest, SizesTooLargeAreRefusedAndTheirSumDoesNotWrap) {
  v1::Manifest manifest;
  for (const char* path : {"a.bin", "b.bin"}) {
    auto* file = manifest.add_files();
    file->set_path(path);
    file->set_size(std::numeric_limits<std::int64_t>::max());
    file->set_sha256(std::string(64, 'a'));
  }
  EXPECT_EQ(TotalBytes(manifest), std::numeric_limits<std::int64_t>::max());
  const std::string message = testing::ErrorFrom([&] { ValidateManifest(manifest); });
  EXPECT_NE(message.find("'a.bin' has size 9223372036854775807, over the"), std::string::npos) << message;
  manifest.mutable_files(0)->set_size(kMaxFileBytes);
  manifest.mutable_files(1)->set_size(2);
  EXPECT_NO_THROW(ValidateManifest(manifest));
  EXPECT_EQ(TotalBytes(manifest), kMaxFileBytes + 2);
}

// A clip of more frames than a results manifest can name trained for nothing: the run could not hand
// its results back, nor `status` and `fetch` show a job whose clip and results manifests together
// exceed a message (a 3,813-frame job; found 2026-12-06). The bound is the measured bytes a frame of
// results takes, beside the clip's manifest.
TEST(ManifestTest, ResultsNoCallCouldCarryAreRefusedNamingHowManyFramesFit) {
  // A clip of 100 bytes of manifest a frame: 1,300 a frame with uncertainty maps, 600 without.
  const std::size_t with = MostManifestBytes() / 1300, without = MostManifestBytes() / 600;
  EXPECT_EQ(with, 3226u);
  CheckResultsFit(with, true, with * 100, "clip");
  CheckResultsFit(without, false, without * 100, "clip");
  const std::string message =
      testing::ErrorFrom([&] { CheckResultsFit(with + 1, true, (with + 1) * 100, "/data/clip"); });
  EXPECT_NE(message.find("/data/clip: 3227 frames: their results would take a manifest of about"),
            std::string::npos)
      << message;
  EXPECT_NE(message.find("At most about 3226 frames of this clip fit with uncertainty maps, " +
                         std::to_string(without) + " without"),
            std::string::npos)
      << message;
  testing::ErrorFrom([&] { CheckResultsFit(without + 1, false, (without + 1) * 100, "clip"); });
  testing::ErrorFrom([&] { CheckResultsFit(1, true, MostManifestBytes(), "clip"); });
  // Every preset writes uncertainty maps; only mc_passes 0 in the job's keys leaves them out.
  EXPECT_TRUE(WritesUncertaintyMaps(nlohmann::json::object()));
  EXPECT_TRUE(WritesUncertaintyMaps({{"mc_passes", 4}, {"iterations", 0}}));
  EXPECT_FALSE(WritesUncertaintyMaps({{"mc_passes", 0}}));

  // The per-frame figure holds for a results folder's names: 11 files a frame with uncertainty maps,
  // 5 without, each a path, a size and a digest.
  v1::Manifest results;
  for (const char* name :
       {"rgb/000123.png", "depth/000123.npy", "depth/000123.png", "error/000123.png", "pointcloud/000123.ply",
        "uncertainty/000123.npy", "uncertainty/000123.png", "uncertainty/000123_aleatoric.npy",
        "uncertainty/000123_epistemic.npy", "uncertainty/000123_model.npy", "uncertainty/000123_model.png"}) {
    auto* file = results.add_files();
    file->set_path(name);
    file->set_size(1 << 20);
    file->set_sha256(std::string(64, 'a'));
  }
  EXPECT_LE(results.ByteSizeLong(), kResultManifestBytesPerFrame);
  results.mutable_files()->DeleteSubrange(5, 6);
  EXPECT_LE(results.ByteSizeLong(), kResultManifestBytesPerFrameWithoutUncertainty);
}

}  // namespace
}  // namespace endorecon
