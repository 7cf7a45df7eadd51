// Depth-prior refinement: after some training, priors corrupted by large errors are the ones the
// rendering disagrees with most, and a round moves them to the rendered depth (close to the truth);
// the rest, the holes and the tool pixels are left alone.
#include "worker/engine/train/depth_refiner.h"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>

#include "common/error.h"
#include "tests/unit/small_clip_fixture.h"
#include "worker/engine/train/trainer.h"

namespace endorecon::train {
namespace {

class DepthRefinerTest : public testing::SmallClipTest {};

bool Tool(const scene::Clip& clip, int f, std::size_t p) { return clip.has_masks() && clip.tool_mask[f][p]; }

// The synthetic clip's priors have holes where its highlights are, as stereo matching leaves; filled
// from their surroundings (depth_fill.h) they come close to the true depth; the tool's pixels stay
// without a prior.
TEST_F(DepthRefinerTest, HolesAreFilledFromTheDepthsAroundThem) {
  const scene::Clip& clip = *clip_;
  const DepthRefiner refiner(clip, AllFrames(), 2.0);
  ASSERT_GT(refiner.filled(), 20u);
  const float range = float(clip.far - clip.near);
  double error = 0;
  std::size_t filled = 0;
  for (int f = 0; f < clip.frame_count(); ++f) {
    for (std::size_t p = 0; p < clip.depth[f].size(); ++p) {
      const float prior = refiner.Prior(f, int(p));
      if (Tool(clip, f, p)) {
        EXPECT_EQ(prior, clip.depth[f][p]) << "frame " << f << " pixel " << p;
      } else if (clip.depth[f][p] > 0) {
        EXPECT_EQ(prior, clip.depth[f][p]) << "frame " << f << " pixel " << p;
      } else if (prior > 0) {
        error += std::fabs(prior - clip.gt_depth[f][p]);
        ++filled;
      }
    }
  }
  EXPECT_EQ(filled, refiner.filled());
  EXPECT_LT(error / double(filled), 0.01 * range) << "mean error of the filled priors";
  EXPECT_EQ(DepthRefiner(clip, AllFrames(), 0.0).filled(), 0u);
}

TEST_F(DepthRefinerTest, MovesTheCorruptedPriorsToTheRenderedDepth) {
  scene::Clip clip = *clip_;  // a copy whose priors this test corrupts
  const float range = float(clip.far - clip.near);
  std::vector<std::vector<char>> corrupted(clip.frame_count());
  for (int f = 0; f < clip.frame_count(); ++f) {
    corrupted[f].assign(clip.depth[f].size(), 0);
    for (std::size_t p = 7; p < clip.depth[f].size(); p += 31) {  // ~3% of the pixels, far off
      if (Tool(clip, f, p) || clip.depth[f][p] <= 0) continue;
      clip.depth[f][p] += 0.2f * range;
      corrupted[f][p] = 1;
    }
  }
  TrainConfig config = SmallConfig();
  config.depth_refine_every = 0;  // only the explicit round below
  config.depth_refine_fraction = 0.1f;
  config.depth_refine_ema = 1.0f;  // EndoNeRF's replacement
  config.depth_fill_sigma = 0;     // the holes stay holes (the next test fills them)
  Trainer trainer(clip, config, AllFrames(), 9);
  for (int i = 0; i < 300; ++i) trainer.Step();

  const DepthRefineStats stats = trainer.RefineDepth();
  EXPECT_EQ(trainer.depth_refiner().rounds(), 1);
  EXPECT_NEAR(double(stats.moved) / double(stats.measured), 0.1, 0.01);

  double before = 0, after = 0;
  std::size_t bad = 0, bad_moved = 0, good_moved = 0, good = 0;
  for (int f = 0; f < clip.frame_count(); ++f) {
    for (std::size_t p = 0; p < clip.depth[f].size(); ++p) {
      const float prior = trainer.depth_refiner().Prior(f, int(p));
      if (clip.depth[f][p] <= 0 || Tool(clip, f, p)) {
        EXPECT_EQ(prior, clip.depth[f][p])
            << "a hole or tool pixel was refined: frame " << f << " pixel " << p;
        continue;
      }
      const bool moved = prior != clip.depth[f][p];
      if (corrupted[f][p]) {
        ++bad;
        bad_moved += moved;
        before += std::fabs(clip.depth[f][p] - clip.gt_depth[f][p]);
        after += std::fabs(prior - clip.gt_depth[f][p]);
      } else {
        ++good;
        good_moved += moved;
      }
    }
  }
  ASSERT_GT(bad, 100u);
  EXPECT_GT(double(bad_moved) / double(bad), 0.9) << "the corrupted priors are the worst ones";
  EXPECT_LT(after, 0.25 * before) << "mean error of the corrupted priors: " << before / bad << " -> "
                                  << after / bad;
  EXPECT_LT(double(good_moved) / double(good), 0.1);
}

TEST_F(DepthRefinerTest, ExponentialMovingAverageMovesAFractionOfTheWay) {
  TrainConfig config = SmallConfig();
  config.depth_refine_every = 0;
  config.depth_fill_sigma = 0;  // priors as the clip has them: what the round is measured against
  config.depth_refine_ema = 0.25f;
  Trainer trainer(*clip_, config, AllFrames(), 4);
  for (int i = 0; i < 50; ++i) trainer.Step();
  const DepthRefiner& refiner = trainer.depth_refiner();
  // Render what the round will compare against, then check every moved prior went a quarter of the way.
  render::FrameRenderSettings settings;
  settings.near = clip_->near;
  settings.far = clip_->far;
  settings.coarse_samples = settings.fine_samples = config.depth_refine_samples;
  settings.floor = config.eval_floor;
  render::FrameRenderer renderer(trainer.field(), trainer.box(), settings);
  const auto frame = renderer.Render(clip_->cameras[2], clip_->times[2]);
  const DepthRefineStats stats = trainer.RefineDepth();
  ASSERT_GT(stats.moved, 0u);
  int checked = 0;
  for (std::size_t p = 0; p < frame.depth.size(); ++p) {
    const float original = clip_->depth[2][p], now = refiner.Prior(2, int(p));
    if (now == original) continue;
    EXPECT_NEAR(now, original + 0.25f * (frame.depth[p] - original), 1e-3f * float(clip_->far)) << p;
    ++checked;
  }
  EXPECT_GT(checked, 0);
}

TEST_F(DepthRefinerTest, BoundedRoundsTakeTheFramesInTurn) {
  TrainConfig config = SmallConfig();
  config.depth_refine_every = 0;
  config.depth_fill_sigma = 0;     // priors as the clip has them: what the round is measured against
  config.depth_refine_pixels = 1;  // one frame a round
  Trainer trainer(*clip_, config, AllFrames(), 4);
  for (int i = 0; i < 20; ++i) trainer.Step();
  const auto measured = [&](int f) {
    std::size_t count = 0;
    for (std::size_t p = 0; p < clip_->depth[f].size(); ++p)
      count += clip_->depth[f][p] > 0 && !Tool(*clip_, f, p);
    return count;
  };
  for (int round = 0; round < clip_->frame_count() + 2; ++round) {
    const int frame = round % clip_->frame_count();
    EXPECT_EQ(trainer.RefineDepth().measured, measured(frame)) << "round " << round;
  }
  // The round after a resume starts where the saved state says.
  std::stringstream state;
  trainer.Save(state);
  Trainer restored(*clip_, config, AllFrames(), 4);
  restored.Load(state);
  EXPECT_EQ(restored.RefineDepth().measured, measured(2));
}

TEST_F(DepthRefinerTest, StateRoundTripsAndRejectsAnotherClipSize) {
  DepthRefiner refiner(*clip_, AllFrames());
  std::stringstream state;
  refiner.Save(state);
  DepthRefiner copy(*clip_, AllFrames());
  copy.Load(state);
  EXPECT_EQ(copy.rounds(), 0);
  EXPECT_EQ(copy.Prior(1, 5), clip_->depth[1][5]);

  scene::Clip shorter = *clip_;
  shorter.cameras.pop_back();
  DepthRefiner other(shorter, {0});
  std::stringstream again(state.str());
  try {
    other.Load(again);
    FAIL() << "loaded refined priors of another clip";
  } catch (const Error& e) {
    EXPECT_EQ(e.code(), ErrorCode::kDataLoss);
  }
}

}  // namespace
}  // namespace endorecon::train
