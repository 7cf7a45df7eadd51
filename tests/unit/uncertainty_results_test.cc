// The uncertainty part of a results folder: per-frame .npy and heat maps with one scale per clip,
// error maps, and calibration for both splits in the metrics.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "common/npy.h"
#include "tests/unit/temp_dir.h"
#include "worker/engine/eval/clip_evaluator.h"
#include "worker/engine/eval/evaluation_mask.h"
#include "worker/engine/eval/exports.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/synthetic_clip.h"
#include "worker/engine/train/render_settings.h"
#include "worker/engine/train/scene_fit.h"
#include "worker/engine/train/trainer.h"

namespace endorecon::eval {
namespace {

TEST(UncertaintyResults, FilesAndOneHeatmapScalePerClip) {
  testing::TempDir dir("uncertainty_results");
  scene::SynthOptions synth;
  synth.frames = 4;
  synth.width = 32;
  synth.height = 24;
  scene::WriteSyntheticClip(synth, dir.path() / "clip");
  const scene::Clip clip = scene::LoadClip(dir.path() / "clip");
  train::TrainConfig config = train::TrainConfig::Preset("cpu");
  config.rays_per_batch = 128;
  config.mc_passes = 3;
  config.eval_coarse_samples = config.eval_fine_samples = 16;
  train::FitToScene(clip, config);
  train::Trainer trainer(clip, config, {0, 1, 2}, 1);
  for (int i = 0; i < 20; ++i) trainer.Step();
  render::FrameRenderer renderer(trainer.field(), trainer.box(),
                                 train::UncertaintyRenderSettings(config, clip.near, clip.far, 5));
  ClipEvaluation what;
  what.train_frames = {0, 1, 2};
  what.heldout_frames = {3};
  const nlohmann::json metrics = EvaluateClip(clip, renderer, what, dir.path() / "out");

  std::vector<std::vector<float>> totals;
  for (int f = 0; f < 4; ++f) {
    for (const char* name :
         {".npy", "_aleatoric.npy", "_epistemic.npy", "_model.npy", ".png", "_model.png"}) {
      EXPECT_TRUE(std::filesystem::exists(dir.path() / "out" / "uncertainty" / FrameFileName(f, name)))
          << f << name;
    }
    EXPECT_TRUE(std::filesystem::exists(dir.path() / "out" / "error" / FrameFileName(f, ".png"))) << f;
    EXPECT_FALSE(std::filesystem::exists(dir.path() / "out" / ".error-maps")) << "the scratch folder is gone";
    totals.push_back(renderer.Render(clip.cameras[f], clip.times[f]).uncertainty);  // deterministic
  }
  // The scales are the tissue's: the tool's pixels left out.
  const auto tissue = [&](std::vector<std::vector<float>> frames) {
    for (int f = 0; f < 4; ++f) {
      const auto& tool = EvaluationMask(clip, f);
      std::vector<float> kept;
      for (std::size_t i = 0; i < frames[f].size(); ++i) {
        if (tool.empty() || tool[i] == 0) kept.push_back(frames[f][i]);
      }
      EXPECT_LT(kept.size(), frames[f].size()) << "the synthetic clip's tool is in frame " << f;
      frames[f] = std::move(kept);
    }
    return frames;
  };
  const auto& maps = metrics.at("uncertainty_maps");
  EXPECT_EQ(maps.at("mc_passes"), 3);
  EXPECT_DOUBLE_EQ(maps.at("heatmap_scale").at("uncertainty").at(1).get<double>(),
                   HeatmapUpperBound(tissue(totals)));
  std::vector<std::vector<float>> models;  // the model maps' heat maps have a scale of their own
  for (int f = 0; f < 4; ++f) {
    const auto map = ReadNpy(dir.path() / "out" / "uncertainty" / FrameFileName(f, "_model.npy")).data;
    models.emplace_back(map.begin(), map.end());
  }
  EXPECT_DOUBLE_EQ(maps.at("heatmap_scale").at("model").at(1).get<double>(),
                   HeatmapUpperBound(tissue(models)));
  for (const char* split : {"train", "heldout"}) {
    const auto& calibration = metrics.at(split).at("calibration");
    EXPECT_TRUE(calibration.contains("spearman")) << split;
    EXPECT_TRUE(calibration.at("curves").contains("oracle")) << split;
    EXPECT_EQ(calibration.at("per_frame").size(), std::string(split) == "train" ? 3u : 1u);
    // The synthetic clip has its noise-free truth (gt/images): calibration against it too.
    const auto& noise_free = metrics.at(split).at("calibration_noise_free");
    EXPECT_TRUE(noise_free.contains("spearman")) << split;
    EXPECT_EQ(noise_free.at("per_frame").size(), calibration.at("per_frame").size()) << split;
    EXPECT_NE(noise_free.at("spearman").at("mean"), calibration.at("spearman").at("mean"))
        << split << ": the noisy images and their truth give different errors";
    // The model map (model_uncertainty.h), against both errors.
    for (const char* key : {"calibration_model_map", "calibration_model_map_noise_free"}) {
      EXPECT_EQ(metrics.at(split).at(key).at("per_frame").size(), calibration.at("per_frame").size()) << key;
    }
    EXPECT_NE(metrics.at(split).at("calibration_model_map").at("spearman").at("mean"),
              calibration.at("spearman").at("mean"))
        << split << ": another map ranks otherwise";
  }
}

}  // namespace
}  // namespace endorecon::eval
