// Guards in training (issue 6 §3): a run whose learning rate is large enough to diverge stops with
// Error(kInternal) naming the stage and the iteration, never with silent NaN, and the checkpoint
// written before the failing step is still there and loads; and gradient clipping keeps a
// gradient too large for float's Adam second moment from stopping the run.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <regex>
#include <string>
#include <vector>

#include "common/error.h"
#include "tests/unit/temp_dir.h"
#include "worker/engine/reconstruct.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/synthetic_clip.h"
#include "worker/engine/train/adam.h"
#include "worker/engine/train/checkpoint.h"
#include "worker/engine/train/trainer.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;

// Every group at the largest rate a configuration takes (1), no decay, and Adam without its second
// moment's memory (beta2 0) and with a vanishing eps: a parameter whose gradient falls to ~0 while
// its momentum does not is moved by momentum / eps, and a later forward pass overflows. (Until
// 2026-12-05 a rate of 1e9 did this; rates above 1 are refused now.)
nlohmann::json DivergingConfig() {
  nlohmann::json lr;
  for (const char* group : {"grid", "density", "color", "blend", "deform"}) lr[group] = 1.0;
  return {{"rays_per_batch", 128},
          {"adam", {{"lr", lr}, {"final_lr_factor", 1.0}, {"beta1", 0.99}, {"beta2", 0.0}, {"eps", 1e-30}}}};
}

// The preset with DivergingConfig's small batch.
nlohmann::json SmallConfig() { return {{"rays_per_batch", 128}}; }

// A 6-frame 40 x 32 synthetic clip in dir/clip.
void WriteClip(const fs::path& dir) {
  scene::SynthOptions synth;
  synth.frames = 6;
  synth.width = 40;
  synth.height = 32;
  scene::WriteSyntheticClip(synth, dir / "clip");
}

TEST(Divergence, ReconstructThrowsNamingStageAndIterationAndKeepsTheLastGoodCheckpoint) {
  testing::TempDir dir("divergence");
  WriteClip(dir.path());

  ReconstructOptions options;
  options.clip_dir = (dir / "clip").string();
  options.out_dir = (dir / "out").string();
  options.config = DivergingConfig();
  options.iterations = 200;
  ReconstructHooks hooks;
  hooks.checkpoint_interval_s = 0;  // a checkpoint after every step that passed its checks
  int checkpoints = 0;
  hooks.on_checkpoint = [&](const std::string&) { ++checkpoints; };
  std::string message;
  try {
    Reconstruct(options, hooks);
    FAIL() << "DivergingConfig trained 200 iterations without a non-finite loss or gradient";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInternal) << e.what();
    message = e.what();
  }
  std::smatch match;
  ASSERT_TRUE(
      std::regex_search(message, match, std::regex("at iteration ([0-9]+) \\(stage: (loss|backward)")))
      << message;
  const int failed_at = std::stoi(match[1]);
  ASSERT_GT(failed_at, 0) << "the run must diverge after at least one good step for this test: " << message;
  EXPECT_EQ(checkpoints, failed_at);

  // Nothing is written on the throw: the checkpoint is that of the last good step, and it loads.
  const fs::path checkpoint = dir / "out" / "model" / "checkpoint.bin";
  ASSERT_TRUE(fs::exists(checkpoint));
  EXPECT_FALSE(fs::exists(dir / "out" / "metrics.json"));
  const scene::Clip clip = scene::LoadClip(dir / "clip");
  const train::TrainConfig config = train::ReadCheckpointConfig(checkpoint);
  EXPECT_FLOAT_EQ(config.adam.lr.at("grid"), 1.0f);
  std::vector<int> frames(clip.frame_count());
  for (int f = 0; f < clip.frame_count(); ++f) frames[f] = f;
  train::Trainer trainer(clip, config, frames, options.seed);
  train::ReadCheckpointState(checkpoint, trainer);
  EXPECT_EQ(trainer.iteration(), failed_at);
  for (const auto& block : trainer.field().Blocks()) {
    for (std::size_t i = 0; i < block.size; ++i) {
      ASSERT_TRUE(std::isfinite(block.value[i]))
          << "checkpointed parameter " << block.name << "[" << i << "]";
    }
  }
}

// What the kept checkpoint is for: a run that diverges leaves the last periodic checkpoint alone,
// and training resumes from it with another configuration (here the learning rates) over the
// checkpoint's own.
TEST(Divergence, TheLastGoodCheckpointResumesWithAnotherConfiguration) {
  testing::TempDir dir("divergence-resume");
  WriteClip(dir.path());

  ReconstructOptions options;
  options.clip_dir = (dir / "clip").string();
  options.out_dir = (dir / "healthy").string();
  options.config = SmallConfig();
  options.iterations = 5;
  Reconstruct(options, {});
  const fs::path good = dir / "healthy" / "model" / "checkpoint.bin";
  ASSERT_TRUE(fs::exists(good));

  // Resumed with the diverging configuration it diverges, and the checkpoint it resumed from is untouched.
  options.resume_from = good.string();
  options.out_dir = (dir / "healthy").string();
  options.config = DivergingConfig();
  options.iterations = 200;
  ReconstructHooks hooks;
  hooks.checkpoint_interval_s = 1e9;
  const auto before = fs::last_write_time(good);
  EXPECT_THROW(Reconstruct(options, hooks), Error);
  EXPECT_EQ(fs::last_write_time(good), before);
  EXPECT_EQ(train::ReadCheckpointConfig(good).adam.lr.at("grid"), 3e-2f);

  // Resumed with the preset's rates it trains on to the end, every parameter finite.
  options.config = SmallConfig();
  options.out_dir = (dir / "resumed").string();
  options.iterations = 10;
  const ReconstructSummary summary = Reconstruct(options, {});
  EXPECT_EQ(summary.iterations, 10);
  EXPECT_TRUE(std::isfinite(summary.train_psnr));
}

// Adam keeps its second moment in float: a gradient above sqrt(FLT_MAX) ~ 1.8e19 would make it Inf
// and freeze that parameter for good (m / sqrt(Inf) = 0) with no NaN anywhere. Adam reports such a
// step as not finite (the trainer then stops naming the group); with clip_norm the gradient is
// scaled down first and the step goes through.
TEST(Divergence, ClippingPreventsTheSecondMomentOverflow) {
  for (float clip : {0.0f, 1.0f}) {
    std::vector<float> value = {0.5f, -0.25f}, grad = {3e19f, 1.0f};
    train::AdamConfig config;
    config.default_lr = 0.01f;
    config.clip_norm = clip;
    train::Adam adam({field::ParamBlock<float>{"grid", value.data(), grad.data(), value.size()}}, config);
    const train::AdamStepReport report = adam.Step(0.0);
    EXPECT_NEAR(report.grad_norm, 3e19, 1e13);
    if (clip == 0.0f) {
      EXPECT_FALSE(report.finite) << "a gradient whose square overflows float went through unclipped";
      EXPECT_EQ(report.bad_group, "grid");
      EXPECT_EQ(value[0], 0.5f) << "a refused step must leave the parameters alone";
    } else {
      ASSERT_TRUE(report.finite);
      // Adam's first step moves a parameter whose gradient dominates eps by lr against its sign.
      EXPECT_NEAR(value[0], 0.49f, 1e-6f);
      // And the next, ordinary step still moves it: nothing froze.
      grad = {1.0f, 1.0f};
      ASSERT_TRUE(adam.Step(0.0).finite);
      EXPECT_LT(value[0], 0.49f - 1e-4f);
    }
  }
}

}  // namespace
}  // namespace endorecon
