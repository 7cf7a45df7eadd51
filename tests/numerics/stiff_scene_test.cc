// The stiff scene (issue 6 §2, `endorecon-worker synth --stiff`): a depth range of ~7 units over a
// tissue ~85 units away (alpha reaches 1 within one sample once the surface forms), near-black tissue
// and saturated speculars. A short reconstruction through Reconstruct finishes, and every output is
// finite: metrics.json (curve included), rendered depth maps, the saved model's parameters.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>

#include "common/npy.h"
#include "tests/numerics/finite_json.h"
#include "tests/unit/temp_dir.h"
#include "worker/engine/reconstruct.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/synthetic_clip.h"
#include "worker/engine/train/checkpoint.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;
using testing::ExpectAllFinite;

TEST(StiffScene, ShortReconstructionHasNoNanOrInf) {
  testing::TempDir dir("stiff");
  scene::SynthOptions synth;
  synth.frames = 12;
  synth.width = 64;
  synth.height = 48;
  synth.stiff = true;
  scene::WriteSyntheticClip(synth, dir / "clip");
  const scene::Clip clip = scene::LoadClip(dir / "clip");
  ASSERT_LT(clip.far - clip.near, 10.0) << "the stiff clip's depth range";

  ReconstructOptions options;
  options.clip_dir = (dir / "clip").string();
  options.out_dir = (dir / "out").string();
  options.config = {{"rays_per_batch", 512}, {"curve_interval_s", 1.0}};
  options.iterations = 300;
  options.holdout = 4;
  const ReconstructSummary summary = Reconstruct(options, {});
  EXPECT_EQ(summary.iterations, 300);
  EXPECT_TRUE(std::isfinite(summary.train_psnr));
  EXPECT_TRUE(std::isfinite(summary.heldout_psnr));

  std::ifstream in(summary.metrics_path);
  const nlohmann::json metrics = nlohmann::json::parse(in);
  ExpectAllFinite(metrics, "metrics");
  ASSERT_GE(metrics["curve"].size(), 2u);
  for (const auto& point : metrics["curve"]) {
    EXPECT_TRUE(point.contains("heldout_psnr")) << point;
    EXPECT_TRUE(point.contains("heldout_depth_rmse_relative")) << point;
  }
  // Learning happened (not merely no NaN): the last training PSNR beats the first.
  EXPECT_GT(metrics["curve"].back()["train_psnr"].get<double>(),
            metrics["curve"].front()["train_psnr"].get<double>());

  for (int f = 0; f < clip.frame_count(); ++f) {
    char name[16];
    std::snprintf(name, sizeof(name), "%06d.npy", f);
    const NpyArray depth = ReadNpy(dir / "out" / "depth" / name);
    ASSERT_EQ(depth.size(), std::size_t(clip.width * clip.height));
    std::size_t without_surface = 0;
    for (double d : depth.data) {
      ASSERT_TRUE(std::isfinite(d)) << "depth/" << name;
      // 0 where the ray met no surface (opacity under eval::kSurfaceOpacity); elsewhere sum w_j s_j +
      // (1 - opacity) far: within [near, far] up to float rounding.
      if (d == 0) {
        ++without_surface;
        continue;
      }
      ASSERT_GE(d, clip.near - 1e-3) << "depth/" << name;
      ASSERT_LE(d, clip.far + 1e-3) << "depth/" << name;
    }
    EXPECT_LT(without_surface, depth.size() / 10) << "depth/" << name << ": the tissue is a surface";
  }
  const train::Model model = train::ReadModel(dir / "out" / "model" / "model.bin");
  for (const auto& block : model.field->Blocks()) {
    for (std::size_t i = 0; i < block.size; ++i) {
      ASSERT_TRUE(std::isfinite(block.value[i])) << "model parameter " << block.name << "[" << i << "]";
    }
  }
}

}  // namespace
}  // namespace endorecon
