// Whole runs on clips with extreme frames (issue 6 §1): every frame all tool, some frames all tool,
// no tool at all, all-black and saturated frames, depth maps of zeros or of one constant value (inside
// and beyond [near, far]). Each clip is written to disk (a small synthetic clip whose files are then
// overwritten) and goes through Reconstruct: LoadClip, FitToScene, a few dozen training steps,
// evaluation. A run either finishes with every number in metrics.json finite and every rendered
// depth finite, or fails up front with an error that says what is wrong.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "common/error.h"
#include "common/npy.h"
#include "tests/numerics/finite_json.h"
#include "tests/unit/temp_dir.h"
#include "worker/engine/reconstruct.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/synthetic_clip.h"
#include "worker/engine/train/ray_sampler.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;
using testing::ExpectAllFinite;

constexpr int kFrames = 8, kWidth = 48, kHeight = 40;

// Writes the small synthetic clip, then replaces frame files: edit(folder, frame) returns the new
// image for images/, masks/ or depth/ (an empty Mat keeps the file).
using Edit = std::function<cv::Mat(const std::string& folder, int frame)>;

fs::path WriteClip(const testing::TempDir& dir, const Edit& edit) {
  scene::SynthOptions synth;
  synth.frames = kFrames;
  synth.width = kWidth;
  synth.height = kHeight;
  const fs::path clip = dir / "clip";
  scene::WriteSyntheticClip(synth, clip);
  for (const char* folder : {"images", "masks", "depth"}) {
    for (int f = 0; f < kFrames; ++f) {
      const cv::Mat image = edit(folder, f);
      if (image.empty()) continue;
      char name[16];
      std::snprintf(name, sizeof(name), "%06d.png", f);
      EXPECT_TRUE(cv::imwrite((clip / folder / name).string(), image)) << folder << "/" << name;
    }
  }
  return clip;
}

cv::Mat Gray(int value) { return cv::Mat(kHeight, kWidth, CV_8UC1, cv::Scalar(value)); }
cv::Mat Colour(int value) { return cv::Mat(kHeight, kWidth, CV_8UC3, cv::Scalar(value, value, value)); }

// 40 iterations, every 4th frame held out, 128 rays a step. Returns metrics.json.
nlohmann::json ReconstructSmall(const testing::TempDir& dir, const fs::path& clip) {
  ReconstructOptions options;
  options.clip_dir = clip.string();
  options.out_dir = (dir / "out").string();
  options.config = {{"rays_per_batch", 128}, {"curve_interval_s", 0.05}};
  options.iterations = 40;
  options.holdout = 4;
  const ReconstructSummary summary = Reconstruct(options, {});
  EXPECT_EQ(summary.iterations, 40);
  std::ifstream in(summary.metrics_path);
  const nlohmann::json metrics = nlohmann::json::parse(in);
  for (int f = 0; f < kFrames; ++f) {
    char name[16];
    std::snprintf(name, sizeof(name), "%06d.npy", f);
    const NpyArray depth = ReadNpy(dir / "out" / "depth" / name);
    EXPECT_EQ(depth.size(), std::size_t(kWidth * kHeight));
    EXPECT_EQ(std::count_if(depth.data.begin(), depth.data.end(), [](double d) { return !std::isfinite(d); }),
              0)
        << "non-finite values in depth/" << name;
  }
  return metrics;
}

TEST(ExtremeClips, EveryFrameAllToolFailsUpFrontNamingTheClip) {
  testing::TempDir dir("extreme-clip");
  const fs::path clip = WriteClip(
      dir, [](const std::string& folder, int) { return folder == "masks" ? Gray(255) : cv::Mat(); });
  const scene::Clip loaded = scene::LoadClip(clip);
  ASSERT_TRUE(loaded.has_masks());
  try {
    train::RaySampler sampler(loaded, {0, 1, 2});
    FAIL() << "a sampler over frames that are all tool";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument);
    EXPECT_NE(std::string(e.what()).find("every pixel is tool"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(clip.string()), std::string::npos) << e.what();
  }
  ReconstructOptions options;
  options.clip_dir = clip.string();
  options.out_dir = (dir / "out").string();
  options.iterations = 5;
  try {
    Reconstruct(options, {});
    FAIL() << "Reconstruct of a clip that is all tool";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInvalidArgument) << e.what();
  }
}

// Frames 1 and 2 (both trained on) are all tool: training draws no ray from them, and their
// per-frame tissue metrics are null (undefined, docs/formats.md) and left out of the summaries,
// which rest on the other frames and are finite; everything else is finite.
TEST(ExtremeClips, SomeFramesAllToolStillTrainAndEvaluate) {
  testing::TempDir dir("extreme-clip");
  const fs::path clip = WriteClip(dir, [](const std::string& folder, int f) {
    return folder == "masks" && (f == 1 || f == 2) ? Gray(255) : cv::Mat();
  });
  nlohmann::json metrics = ReconstructSmall(dir, clip);
  const auto frames = metrics["train"]["frames"].get<std::vector<int>>();
  ASSERT_EQ(frames, (std::vector<int>{0, 1, 2, 4, 5, 6}));
  int sections = 0;
  for (auto& [kind, section] : metrics["train"].items()) {
    if (!section.is_object() || !section.contains("per_frame")) continue;
    ++sections;
    auto& per_frame = section["per_frame"];
    ASSERT_EQ(per_frame.size(), frames.size()) << kind;
    for (int k : {2, 1}) {  // frames 1 and 2, erased from the back
      bool undefined = false;
      for (const auto& [name, value] : per_frame[k].items()) undefined = undefined || value.is_null();
      EXPECT_TRUE(undefined) << kind << " of an all-tool frame: " << per_frame[k];
      per_frame.erase(per_frame.begin() + k);
    }
  }
  EXPECT_GE(sections, 2) << "image and depth metrics at least";
  EXPECT_EQ(metrics["train"]["image"]["psnr_tissue"]["count"].get<int>(), 4);
  ExpectAllFinite(metrics, "metrics");
}

TEST(ExtremeClips, NoToolAnywhere) {
  testing::TempDir dir("extreme-clip");
  const fs::path clip =
      WriteClip(dir, [](const std::string& folder, int) { return folder == "masks" ? Gray(0) : cv::Mat(); });
  ExpectAllFinite(ReconstructSmall(dir, clip), "metrics");
}

TEST(ExtremeClips, AllBlackFrames) {
  testing::TempDir dir("extreme-clip");
  const fs::path clip = WriteClip(
      dir, [](const std::string& folder, int) { return folder == "images" ? Colour(0) : cv::Mat(); });
  const scene::Clip loaded = scene::LoadClip(clip);
  for (const auto& frame : loaded.rgb) {
    for (auto v : frame) ASSERT_EQ(v, 0);
  }
  ExpectAllFinite(ReconstructSmall(dir, clip), "metrics");
}

TEST(ExtremeClips, SaturatedFrames) {
  testing::TempDir dir("extreme-clip");
  const fs::path clip = WriteClip(
      dir, [](const std::string& folder, int) { return folder == "images" ? Colour(255) : cv::Mat(); });
  ExpectAllFinite(ReconstructSmall(dir, clip), "metrics");
}

// Depth maps of zeros are "no value" everywhere: the clip loads as one without depth (no depth loss,
// stratified sampling), and the run's numbers stay finite.
TEST(ExtremeClips, DepthMapsOfZeros) {
  testing::TempDir dir("extreme-clip");
  const fs::path clip =
      WriteClip(dir, [](const std::string& folder, int) { return folder == "depth" ? Gray(0) : cv::Mat(); });
  EXPECT_FALSE(scene::LoadClip(clip).has_depth());
  ExpectAllFinite(ReconstructSmall(dir, clip), "metrics");
}

// One constant value: inside [near, far] = [40, 130] (a flat wall at 85), and beyond far (255).
TEST(ExtremeClips, DepthMapsOfOneConstantValue) {
  for (int value : {85, 255}) {
    testing::TempDir dir("extreme-clip");
    const fs::path clip = WriteClip(
        dir, [value](const std::string& folder, int) { return folder == "depth" ? Gray(value) : cv::Mat(); });
    SCOPED_TRACE("depth " + std::to_string(value));
    ExpectAllFinite(ReconstructSmall(dir, clip), "metrics");
  }
}

// Black frames whose depth says a flat wall at one depth, and saturated frames with no depth value:
// two extremes at once.
TEST(ExtremeClips, CombinedExtremes) {
  for (int colour : {0, 255}) {
    testing::TempDir dir("extreme-clip");
    const fs::path clip = WriteClip(dir, [colour](const std::string& folder, int) {
      if (folder == "images") return Colour(colour);
      if (folder == "depth") return Gray(colour == 0 ? 85 : 0);
      return cv::Mat();
    });
    SCOPED_TRACE("colour " + std::to_string(colour));
    ExpectAllFinite(ReconstructSmall(dir, clip), "metrics");
  }
}

}  // namespace
}  // namespace endorecon
