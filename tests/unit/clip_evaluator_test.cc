// The clip evaluator's image metrics: against the observed images, and against a synthetic clip's
// noise-free truth (gt/images), which differ exactly by the camera's noise; the model map's
// neighbours; a plan kept to its deadline.
#include "worker/engine/eval/clip_evaluator.h"

#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <nlohmann/json.hpp>
#include <vector>

#include "common/npy.h"
#include "tests/unit/clip_fixture.h"
#include "tests/unit/temp_dir.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/outside_view.h"
#include "worker/engine/scene/synthetic_clip.h"
#include "worker/engine/train/render_settings.h"
#include "worker/engine/train/scene_fit.h"
#include "worker/engine/train/trainer.h"

namespace endorecon::eval {
namespace {

// A tiny synthetic clip (32 x 24; `synth` says the rest) written to dir/clip and loaded, and a field
// trained on it for a few steps (the cpu preset at 128 rays a step, with `mc_passes` dropout passes)
// with a renderer of it.
struct BrieflyTrained {
  BrieflyTrained(scene::SynthOptions synth, const std::filesystem::path& dir, std::vector<int> train_frames,
                 int mc_passes, int steps)
      : clip(Load(synth, dir)),
        config(Config(clip, mc_passes)),
        trainer(clip, config, std::move(train_frames), 1) {
    for (int i = 0; i < steps; ++i) trainer.Step();
  }

  static scene::Clip Load(scene::SynthOptions synth, const std::filesystem::path& dir) {
    synth.width = 32;
    synth.height = 24;
    scene::WriteSyntheticClip(synth, dir / "clip");
    return scene::LoadClip(dir / "clip");
  }

  static train::TrainConfig Config(const scene::Clip& clip, int mc_passes) {
    train::TrainConfig config = train::TrainConfig::Preset("cpu");
    config.rays_per_batch = 128;
    config.mc_passes = mc_passes;
    train::FitToScene(clip, config);
    return config;
  }

  scene::Clip clip;
  train::TrainConfig config;
  train::Trainer trainer;
  render::FrameRenderer renderer{trainer.field(), trainer.box(),
                                 train::UncertaintyRenderSettings(config, clip.near, clip.far, 5)};
};

// A few steps on a tiny clip, evaluated without uncertainty (the image metrics only).
nlohmann::json Evaluate(bool noise, const std::filesystem::path& dir, scene::Clip* loaded) {
  scene::SynthOptions synth;
  synth.frames = 3;
  synth.noise = noise ? 1 : 0;
  BrieflyTrained run(synth, dir, {0, 2}, 0, 10);
  *loaded = run.clip;
  ClipEvaluation what;
  what.train_frames = {0, 2};
  what.heldout_frames = {1};
  what.write_files = false;
  return EvaluateClip(run.clip, run.renderer, what, dir / "out");
}

TEST(ClipEvaluatorTest, ImagesAreMeasuredAgainstTheNoiseFreeTruthToo) {
  testing::TempDir dir("clip_evaluator");
  scene::Clip clip;
  const nlohmann::json metrics = Evaluate(true, dir.path(), &clip);
  ASSERT_FALSE(clip.gt_rgb.empty());
  for (const char* split : {"train", "heldout"}) {
    const auto& observed = metrics.at(split).at("image").at("per_frame");
    const auto& truth = metrics.at(split).at("image_noise_free").at("per_frame");
    ASSERT_EQ(truth.size(), observed.size()) << split;
    for (std::size_t i = 0; i < truth.size(); ++i) {
      EXPECT_NE(truth[i].at("psnr_tissue").get<double>(), observed[i].at("psnr_tissue").get<double>())
          << split << " frame " << i << ": the camera's noise is in the images, not in their truth";
    }
  }
  EXPECT_TRUE(metrics.at("heldout").at("image_noise_free").contains("against"));
  // Held-out frames are also scored after their exposure is fitted (gain_fit.h), never worse.
  for (const char* key : {"image", "image_noise_free"}) {
    const std::string fitted = std::string(key) + "_gain_fitted";
    EXPECT_FALSE(metrics.at("train").contains(fitted)) << "a training frame's exposure is trained";
    EXPECT_GE(metrics.at("heldout").at(fitted).at("psnr_tissue").at("mean").get<double>(),
              metrics.at("heldout").at(key).at("psnr_tissue").at("mean").get<double>())
        << key;
  }
}

TEST(ClipEvaluatorTest, WithoutNoiseTheTruthScoresAsTheImages) {
  testing::TempDir dir("clip_evaluator_clean");
  scene::Clip clip;
  const nlohmann::json metrics = Evaluate(false, dir.path(), &clip);
  for (const char* split : {"train", "heldout"}) {
    const auto& observed = metrics.at(split).at("image").at("per_frame");
    const auto& truth = metrics.at(split).at("image_noise_free").at("per_frame");
    ASSERT_EQ(truth.size(), observed.size()) << split;
    for (std::size_t i = 0; i < truth.size(); ++i) {
      // gt/images lacks only the tool, which the tissue numbers leave out.
      EXPECT_DOUBLE_EQ(truth[i].at("psnr_tissue").get<double>(), observed[i].at("psnr_tissue").get<double>())
          << split << " frame " << i;
    }
  }
}

// The model map of a held-out frame carries its neighbours' residuals and its render's disagreement
// with their images (neighbour_evidence.h): the same field evaluated on a clip whose training frames 1
// and 3 are wrong in a block of pixels (the render is unchanged; only their residual grows there)
// raises held-out frame 2's block above the rest.
TEST(ClipEvaluatorTest, AHeldOutFramesModelMapSeesItsNeighboursResiduals) {
  testing::TempDir dir("clip_evaluator_neighbours");
  scene::SynthOptions synth;
  synth.frames = 5;
  synth.tool = false;
  BrieflyTrained run(synth, dir.path(), {0, 1, 3, 4}, 4, 60);
  const scene::Clip& clip = run.clip;
  ClipEvaluation what;
  what.train_frames = {0, 1, 3, 4};
  what.heldout_frames = {2};
  const auto model_map = [&](const scene::Clip& evaluated, const char* out) {
    EvaluateClip(evaluated, run.renderer, what, dir / out);
    return ReadNpy(dir / out / "uncertainty" / "000002_model.npy").data;
  };
  const std::vector<double> plain = model_map(clip, "plain");
  scene::Clip wrong = clip;
  const auto in_block = [&](int p, int margin = 0) {
    return p % clip.width >= 10 - margin && p % clip.width < 14 + margin && p / clip.width >= 8 - margin &&
           p / clip.width < 12 + margin;
  };
  for (int f : {1, 3}) {
    for (int p = 0; p < clip.width * clip.height; ++p) {
      if (!in_block(p)) continue;
      for (int c = 0; c < 3; ++c) wrong.rgb[f][3 * p + c] = wrong.rgb[f][3 * p + c] > 127 ? 0 : 255;
    }
  }
  const std::vector<double> seen = model_map(wrong, "wrong");
  ASSERT_EQ(seen.size(), plain.size());
  // The block's values rise and every other pixel's beyond the disagreement's blur falls (the terms
  // count relative to their means), so the block stands well above the rest though the render is the
  // same.
  double block = 0, rest = 0;
  int rest_count = 0;
  for (int p = 0; p < int(seen.size()); ++p) {
    if (in_block(p)) {
      EXPECT_GT(seen[p], plain[p]) << "pixel " << p;
      block += seen[p] / 16;
    } else if (!in_block(p, 4)) {  // 4 pixels: the reach of the blur (σ 1 pixel, 9 taps)
      EXPECT_LE(seen[p], plain[p]) << "pixel " << p;
      rest += seen[p];
      ++rest_count;
    }
  }
  EXPECT_GT(block, 2.5 * rest / rest_count);
}

// A plan priced far too low meets its deadline anyway: with the deadline already past, every frame,
// the held-out one too, is rendered reduced at the coarsest stride (FramePacer), and metrics.json says
// which frames went coarser and which held-out frames were reduced.
TEST(ClipEvaluatorTest, APlanPricedTooLowIsKeptToItsDeadline) {
  testing::TempDir dir("clip_evaluator_late");
  scene::SynthOptions synth;
  synth.frames = 5;
  BrieflyTrained run(synth, dir.path(), {0, 1, 3, 4}, 2, 10);
  render::FrameRenderer plain(run.trainer.field(), run.trainer.box(),
                              train::ReducedRenderSettings(run.config, run.clip.near, run.clip.far));
  ClipEvaluation what;
  what.train_frames = {0, 1, 3, 4};
  what.heldout_frames = {2};
  what.write_files = false;
  what.plain = &plain;
  what.plan.frames = {FrameRender::kFull, FrameRender::kReduced, FrameRender::kFull, FrameRender::kReduced,
                      FrameRender::kReduced};
  what.plan.stride = 2;
  what.plan.cost = {1e-9, 1e-10};  // a thousandth of a second a frame: far below what it takes
  what.plan.seconds = 5e-6;
  const auto evaluate = [&](std::chrono::steady_clock::time_point deadline) {
    what.deadline = deadline;
    return EvaluateClip(run.clip, run.renderer, what, dir / "out").at("evaluation");
  };
  const nlohmann::json late = evaluate(std::chrono::steady_clock::now());
  EXPECT_EQ(late.at("full_frames"), nlohmann::json::array());
  EXPECT_EQ(late.at("reduced_frames"), nlohmann::json::array({0, 1, 2, 3, 4}));
  EXPECT_EQ(late.at("heldout_reduced"), nlohmann::json::array({2}));
  EXPECT_EQ(late.at("uncertainty_stride").get<int>(), 2);
  ASSERT_TRUE(late.contains("uncertainty_stride_late"));
  const auto& coarser = late.at("uncertainty_stride_late");
  ASSERT_EQ(coarser.size(), 5u);
  for (std::size_t i = 0; i < coarser.size(); ++i) {
    EXPECT_EQ(coarser[i].at("frame").get<int>(), int(i));
    EXPECT_EQ(coarser[i].at("stride").get<int>(), 4);
  }
  EXPECT_DOUBLE_EQ(late.at("seconds").at("render_planned").get<double>(), 5e-6);
  // With time to spare the plan is kept as it is.
  const nlohmann::json on_time = evaluate(std::chrono::steady_clock::now() + std::chrono::hours(1));
  EXPECT_EQ(on_time.at("full_frames"), nlohmann::json::array({0, 2}));
  EXPECT_FALSE(on_time.contains("uncertainty_stride_late"));
  EXPECT_FALSE(on_time.contains("heldout_reduced"));
  // What the frames as rendered cost at the plan's prices, which rendering took far longer than:
  // reconstruct.cc reprices the leanest plan by that pace.
  const int pixels = scene::RenderedPixels(run.clip);
  double priced = 0;
  for (const FrameRender how : what.plan.frames) priced += FrameSeconds(how, 2, what.plan.cost, pixels);
  EXPECT_DOUBLE_EQ(on_time.at("seconds").at("render_priced").get<double>(), priced);
  EXPECT_GT(on_time.at("seconds").at("render").get<double>(), 100 * priced);
  EXPECT_DOUBLE_EQ(late.at("seconds").at("render_priced").get<double>(),
                   5 * FrameSeconds(FrameRender::kReduced, 4, what.plan.cost, pixels));
  // A plan that reduces the held-out frame (a budget too small for full ones) says so; with the
  // time to spare the pacer renders it full after all.
  what.plan.frames[2] = FrameRender::kReduced;
  const nlohmann::json lean = evaluate(std::chrono::steady_clock::time_point::max());
  EXPECT_EQ(lean.at("heldout_reduced"), nlohmann::json::array({2}));
  const nlohmann::json ahead = evaluate(std::chrono::steady_clock::now() + std::chrono::hours(1));
  EXPECT_FALSE(ahead.contains("heldout_reduced"));
  EXPECT_EQ(ahead.at("full_frames"), nlohmann::json::array({0, 2}));
  // Without uncertainty (mc_passes 0) there are no maps, so no stride to name, late or not (a
  // stride of 2 and frames gone to 4 were written until 2026-12-07).
  auto settings = train::EvalRenderSettings(run.config, run.clip.near, run.clip.far);
  settings.mc_passes = 0;
  render::FrameRenderer mapless(run.trainer.field(), run.trainer.box(), settings);
  what.deadline = std::chrono::steady_clock::now();
  const nlohmann::json none = EvaluateClip(run.clip, mapless, what, dir / "mapless").at("evaluation");
  EXPECT_EQ(none.at("reduced_frames"), nlohmann::json::array({0, 1, 2, 3, 4}));
  EXPECT_FALSE(none.contains("uncertainty_stride")) << none.dump();
  EXPECT_FALSE(none.contains("uncertainty_stride_late")) << none.dump();
}

// Outside the scope's view every uncertainty map written holds 0, on full and reduced frames alike:
// the reduced frames' upsampled maps and the model maps held values there (found 2026-12-05).
// A stop asked for while the frames render (a cancel, a worker's shutdown) is heeded before the next
// frame, with the files of the frame in flight written: CANCELLED, saying how far it got.
TEST(ClipEvaluatorTest, AStopIsHeededBeforeTheNextFrame) {
  testing::TempDir dir("clip_evaluator_stop");
  scene::SynthOptions synth;
  synth.frames = 5;
  BrieflyTrained run(synth, dir.path(), {0, 1, 3, 4}, 2, 10);
  ClipEvaluation what;
  what.train_frames = {0, 1, 3, 4};
  what.heldout_frames = {2};
  // Asked before each frame and before each of its chunks (1,024 rays by default: a large frame with
  // uncertainty took 20-30 s, a stop waiting for it; found 2026-12-07). Chunks of 256 rays here, so
  // the small frame has several.
  auto settings = run.renderer.settings();
  settings.rays_per_chunk = 256;
  render::FrameRenderer chunked(run.trainer.field(), run.trainer.box(), settings);
  const int chunks =
      (run.clip.width * run.clip.height + settings.rays_per_chunk - 1) / settings.rays_per_chunk;
  ASSERT_GT(chunks, 1) << "the test's premise: a frame of several chunks";
  const int per_frame = 1 + chunks;
  for (const int answered_no : {2 * per_frame, 2 * per_frame + 2}) {  // before frame 2, within it
    int asked = 0;
    what.should_stop = [&] { return ++asked > answered_no; };
    const std::filesystem::path out = dir / ("out" + std::to_string(answered_no));
    const std::string stopped =
        testing::ErrorFrom([&] { EvaluateClip(run.clip, chunked, what, out); }, ErrorCode::kCancelled);
    EXPECT_NE(stopped.find("2 of 5 frames rendered"), std::string::npos) << stopped;
    EXPECT_EQ(asked, answered_no + 1);
    EXPECT_TRUE(std::filesystem::exists(out / "rgb" / "000001.png"));
    EXPECT_FALSE(std::filesystem::exists(out / "rgb" / "000002.png"));
  }
  // The renderer's stop is its own again: a render after the evaluation is not stopped.
  EXPECT_NO_THROW(chunked.Render(run.clip.cameras[0], run.clip.times[0]));
}

TEST(ClipEvaluatorTest, OutsideTheViewEveryMapIsZero) {
  testing::TempDir dir("clip_evaluator_outside");
  scene::SynthOptions synth;
  synth.frames = 4;
  BrieflyTrained run(synth, dir.path(), {0, 1, 3}, 2, 10);
  const int w = run.clip.width, h = run.clip.height;
  std::vector<std::uint8_t> outside(std::size_t(w) * h, 0);
  for (int y = 0; y < h; ++y) {
    for (int x = 0; x < 5; ++x) outside[std::size_t(y) * w + x] = 1;  // the left five columns
  }
  scene::ExcludeFromFrames(run.clip, outside);
  render::FrameRenderer plain(run.trainer.field(), run.trainer.box(),
                              train::ReducedRenderSettings(run.config, run.clip.near, run.clip.far));
  ClipEvaluation what;
  what.train_frames = {0, 1, 3};
  what.heldout_frames = {2};
  what.plain = &plain;
  what.plan.frames = {FrameRender::kFull, FrameRender::kReduced, FrameRender::kFull, FrameRender::kReduced};
  what.plan.stride = 2;
  EvaluateClip(run.clip, run.renderer, what, dir / "out");
  for (int f = 0; f < 4; ++f) {
    for (const char* suffix : {".npy", "_aleatoric.npy", "_epistemic.npy", "_model.npy"}) {
      char name[32];
      std::snprintf(name, sizeof(name), "%06d%s", f, suffix);
      const NpyArray map = ReadNpy(dir / "out" / "uncertainty" / name);
      ASSERT_EQ(map.data.size(), outside.size()) << name;
      int inside_nonzero = 0;
      for (std::size_t i = 0; i < outside.size(); ++i) {
        if (outside[i]) {
          ASSERT_EQ(map.data[i], 0.0) << name << " pixel " << i;
        } else {
          inside_nonzero += map.data[i] != 0;
        }
      }
      EXPECT_GT(inside_nonzero, 0) << name;
    }
  }
}

}  // namespace
}  // namespace endorecon::eval
