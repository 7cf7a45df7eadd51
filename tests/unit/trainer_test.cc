// Training on a small synthetic clip: the error falls below a bound, a fixed seed on one thread
// gives the same run twice, and a checkpoint resumes onto the same loss curve.
#include "worker/engine/train/trainer.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <cstdio>
#include <sstream>
#include <string>

#include "common/error.h"
#include "tests/unit/object_clip.h"
#include "tests/unit/small_clip_fixture.h"
#include "worker/engine/eval/psnr.h"
#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/scene_box.h"
#include "worker/engine/scene/synthetic_clip.h"
#include "worker/engine/train/render_settings.h"
#include "worker/engine/train/scene_fit.h"

namespace endorecon::train {
namespace {

class TrainerTest : public testing::SmallClipTest {};

TEST_F(TrainerTest, ErrorFallsBelowBound) {
  Trainer trainer(*clip_, SmallConfig(), AllFrames(), 7);
  double first = 0, last = 0;
  for (int i = 0; i < 300; ++i) {
    const StepStats stats = trainer.Step();
    ASSERT_TRUE(std::isfinite(stats.loss)) << "iteration " << i;
    if (i < 10) first += stats.psnr / 10;
    if (i >= 290) last += stats.psnr / 10;
  }
  EXPECT_GT(last, first + 6.0) << "PSNR went from " << first << " to " << last;
  EXPECT_GT(last, 20.0);
}

// The CPU preset for a small object capture: 256 rays a step, `iterations` steps, on `background`,
// fitted to the clip.
TrainConfig ObjectConfig(const scene::Clip& clip, const char* background, int iterations) {
  TrainConfig config = TrainConfig::Preset("cpu");
  config.rays_per_batch = 256;
  config.iterations = iterations;
  config.background = background;
  FitToScene(clip, config);
  return config;
}

// An object capture on transparency (synth --object): "auto" resolves to the white it was composited
// onto, and training against it fits; a black background the images never had fits worse (the
// rays that miss the object's box cannot turn white).
TEST(ObjectTrainerTest, AnObjectCaptureTrainsOnItsWhiteBackground) {
  testing::TempDir dir("object-clip");
  const scene::Clip clip = testing::ObjectClip(dir.path(), 12, 40);
  std::vector<int> frames(clip.frame_count());
  for (int i = 0; i < clip.frame_count(); ++i) frames[i] = i;
  double psnr[2] = {0, 0};
  for (const char* background : {"auto", "black"}) {
    const TrainConfig config = ObjectConfig(clip, background, 300);
    if (background == std::string("auto")) {
      EXPECT_EQ(config.background, "white");
    }
    Trainer trainer(clip, config, frames, 7);
    double last = 0;
    for (int i = 0; i < 300; ++i) {
      const StepStats stats = trainer.Step();
      ASSERT_TRUE(std::isfinite(stats.loss)) << background << " iteration " << i;
      if (i >= 280) last += stats.psnr / 20;
    }
    psnr[background == std::string("black")] = last;
  }
  EXPECT_GT(psnr[0], 20.0) << "white background";
  std::printf("object capture after 300 steps: white %.2f dB, black %.2f dB\n", psnr[0], psnr[1]);
  EXPECT_GT(psnr[0], psnr[1] + 2.5) << "white " << psnr[0] << " dB against black " << psnr[1];
}

// An object in front of a backdrop whose colour depends on the direction (synth --object --backdrop):
// opaque images, which "auto" trains with a learned background. The field can paint the backdrop onto the far
// walls of its box for the views it trains on, but not for others: on held-out views a learned background
// renders the backdrop, black does not.
TEST(ObjectTrainerTest, ACaptureInFrontOfABackdropShowsItsBackdropToNewViewsWithALearnedBackground) {
  testing::TempDir dir("backdrop-clip");
  const scene::Clip clip = testing::ObjectClip(dir.path(), 24, 40, /*backdrop=*/true);
  EXPECT_FALSE(clip.transparent);
  std::vector<int> frames, held_out;
  for (int f = 0; f < clip.frame_count(); ++f) (f % 6 == 5 ? held_out : frames).push_back(f);
  double psnr[2] = {0, 0};
  for (const char* background : {"auto", "black"}) {
    const TrainConfig config = ObjectConfig(clip, background, 500);
    EXPECT_EQ(config.background, background == std::string("auto") ? "learned" : "black");
    EXPECT_EQ(config.field.learned_background, background == std::string("auto"));
    Trainer trainer(clip, config, frames, 7);
    for (int i = 0; i < config.iterations; ++i) {
      ASSERT_TRUE(std::isfinite(trainer.Step().loss)) << background << " iteration " << i;
    }
    render::FrameRenderer renderer(trainer.field(), scene::ClipBox(clip),
                                   EvalRenderSettings(config, clip.near, clip.far));
    for (const int f : held_out) {
      const render::RenderedFrame frame = renderer.Render(clip.cameras[f], clip.times[f]);
      psnr[background == std::string("black")] +=
          eval::Psnr(frame.rgb, clip.rgb[f], {}, clip.width, clip.height) / double(held_out.size());
    }
  }
  std::printf("backdrop capture, held-out views after 500 steps: learned %.2f dB, black %.2f dB\n", psnr[0],
              psnr[1]);
  EXPECT_GT(psnr[0], psnr[1] + 2.0) << "learned " << psnr[0] << " dB against black " << psnr[1];
}

// FitToScene sets the field's background with the run's; a trainer refuses the two apart.
TEST(ObjectTrainerTest, ALearnedBackgroundNeedsTheFieldsModule) {
  testing::TempDir dir("object-clip");
  const scene::Clip clip = testing::ObjectClip(dir.path(), 4, 16);
  TrainConfig config = TrainConfig::Preset("cpu");
  config.background = "learned";
  EXPECT_THROW(Trainer(clip, config, {0, 1, 2, 3}, 7), Error);
}

TEST_F(TrainerTest, FixedSeedOnOneThreadRepeats) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  std::vector<double> a, b;
  for (auto* losses : {&a, &b}) {
    Trainer trainer(*clip_, SmallConfig(), AllFrames(), 11);
    for (int i = 0; i < 15; ++i) losses->push_back(trainer.Step().loss);
  }
  EXPECT_EQ(a, b);
}

// Progress that leaps over several rounds' times at once (a budget revised down) makes one round,
// not one a step for each (a 10 s run made three in nine steps; found 2026-12-06).
TEST_F(TrainerTest, AProgressLeapMakesOneRefinementRoundForAll) {
  TrainConfig config = SmallConfig();
  ASSERT_GT(config.depth_weight, 0);
  config.depth_refine_every = 0.25;
  Trainer trainer(*clip_, config, AllFrames(), 7);
  EXPECT_FALSE(trainer.Step(0.1).depth_refined);
  EXPECT_TRUE(trainer.Step(0.8).depth_refined) << "the times of 0.25, 0.5 and 0.75 have passed";
  EXPECT_EQ(trainer.depth_refiner().rounds(), 3);
  EXPECT_FALSE(trainer.Step(0.81).depth_refined);
  EXPECT_FALSE(trainer.Step(0.82).depth_refined);
  EXPECT_FALSE(trainer.Step(0.99).depth_refined);
  EXPECT_TRUE(trainer.Step(1.0).depth_refined) << "the next time still comes";
}

TEST_F(TrainerTest, CheckpointResumesTheSameCurve) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  // Depth refinement at iterations 5, 10 and 15: the saved state holds refined priors, and the
  // resumed run refines on the same schedule.
  TrainConfig config = SmallConfig();
  config.iterations = 100;
  config.depth_refine_every = 0.05;
  Trainer original(*clip_, config, AllFrames(), 3);
  for (int i = 0; i < 10; ++i) original.Step();
  std::stringstream state;
  original.Save(state);
  std::vector<double> expected, resumed;
  for (int i = 0; i < 10; ++i) expected.push_back(original.Step().loss);

  Trainer restored(*clip_, config, AllFrames(), 3);
  EXPECT_NE(restored.deformation_start().skipped.find("not fitted yet"), std::string::npos)
      << "before a step or a load: " << restored.deformation_start().skipped;
  restored.Load(state);
  EXPECT_EQ(restored.iteration(), 10);
  // The deformation's start was fitted once, in the first run; the resumed one takes the checkpoint's.
  EXPECT_TRUE(original.deformation_start().skipped.empty()) << original.deformation_start().skipped;
  EXPECT_GT(original.deformation_start().points, 0u);
  EXPECT_NE(restored.deformation_start().skipped.find("checkpoint"), std::string::npos)
      << restored.deformation_start().skipped;
  EXPECT_EQ(restored.depth_refiner().rounds(), 1);
  std::stringstream again;
  restored.Save(again);
  EXPECT_TRUE(again.str() == state.str()) << "state changed in a save/load round trip";
  for (int i = 0; i < 10; ++i) resumed.push_back(restored.Step().loss);
  EXPECT_EQ(expected, resumed);
  EXPECT_EQ(restored.depth_refiner().rounds(), 3);
}

TEST_F(TrainerTest, DivergenceIsReportedNotSilent) {
  TrainConfig config = SmallConfig();
  config.adam.lr = {{"grid", 1e9f}, {"density", 1e9f}, {"color", 1e9f}, {"blend", 1e9f}, {"deform", 1e9f}};
  config.adam.final_lr_factor = 1.0f;
  Trainer trainer(*clip_, config, AllFrames(), 5);
  try {
    for (int i = 0; i < 200; ++i) trainer.Step();
    FAIL() << "a learning rate of 1e9 trained for 200 iterations without a non-finite loss or gradient";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kInternal);
    EXPECT_NE(std::string(e.what()).find("iteration"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace endorecon::train
