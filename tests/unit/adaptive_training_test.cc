// Uncertainty-guided adaptive sampling in training: the map never gives a tool pixel and favours
// uncertain cells; training with it converges, repeats with a fixed seed and resumes exactly.
#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <sstream>

#include "tests/unit/small_clip_fixture.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/synthetic_clip.h"
#include "worker/engine/train/scene_fit.h"
#include "worker/engine/train/trainer.h"
#include "worker/engine/train/uncertainty_map.h"

namespace endorecon::train {
namespace {

class AdaptiveTrainingTest : public testing::SmallClipTest {
 protected:
  static TrainConfig AdaptiveConfig() {
    TrainConfig config = SmallConfig();
    config.adaptive_warmup = 0.0;  // guided rays from the first step
    config.adaptive_refresh = 7;
    return config;
  }
};

TEST_F(AdaptiveTrainingTest, MapNeverPicksToolPixelsAndFavoursUncertainCells) {
  ASSERT_TRUE(clip_->has_masks());
  const RaySampler sampler(*clip_, AllFrames());
  UncertaintyMap map(sampler, clip_->width, clip_->height, 4);
  EXPECT_FALSE(map.Pick(1, 2).has_value());  // no scores yet
  // Every cell scores 1, except one tissue cell that scores 100 and cells touching the tool, which
  // score 50 (so rejection inside a mixed cell is exercised).
  std::vector<float> scores(map.cells(), 1.0f);
  int hot = -1, tool_cells = 0, mixed_cells = 0;
  for (int i = 0; i < map.cells(); ++i) {
    const RayPick probe = map.probe(i);
    if (probe.pixel < 0) {
      ++tool_cells;
      scores[i] = 1e6f;  // must be ignored: the cell has no tissue
      continue;
    }
    if (clip_->tool_mask[probe.frame][probe.pixel] == 0 && hot < 0 && i > 10) hot = i;
    const int x = probe.pixel % clip_->width, y = probe.pixel / clip_->width;
    for (int dy = -3; dy <= 3; ++dy) {
      for (int dx = -3; dx <= 3; ++dx) {
        const int xx = x + dx, yy = y + dy;
        if (xx >= 0 && yy >= 0 && xx < clip_->width && yy < clip_->height &&
            clip_->tool_mask[probe.frame][yy * clip_->width + xx]) {
          scores[i] = 50.0f;
        }
      }
    }
    mixed_cells += scores[i] == 50.0f;
  }
  ASSERT_GE(hot, 0);
  EXPECT_GT(tool_cells + mixed_cells, 0);
  scores[hot] = 100.0f;
  map.Set(scores, 0);
  const RayPick hot_probe = map.probe(hot);
  int in_hot = 0;
  const int draws = 20000;
  for (int i = 0; i < draws; ++i) {
    const auto pick = map.Pick(3, std::uint64_t(i));
    ASSERT_TRUE(pick.has_value());
    ASSERT_EQ(clip_->tool_mask[pick->frame][pick->pixel], 0) << "tool pixel picked at draw " << i;
    const int dx = pick->pixel % clip_->width - hot_probe.pixel % clip_->width;
    const int dy = pick->pixel / clip_->width - hot_probe.pixel / clip_->width;
    in_hot += pick->frame == hot_probe.frame && std::abs(dx) < 4 && std::abs(dy) < 4 && scores[hot] == 100.0f;
  }
  double total = 0;
  for (int i = 0; i < map.cells(); ++i) total += map.probe(i).pixel >= 0 ? scores[i] : 0.0;
  // The hot cell's share is 100 / total; a uniform pick would give it 1 / cells.
  EXPECT_GT(double(in_hot) / draws, 0.5 * 100.0 / total);
  EXPECT_GT(double(in_hot) / draws, 5.0 / map.cells());  // at least five times a uniform pick
}

TEST_F(AdaptiveTrainingTest, ConvergesWithGuidedRays) {
  Trainer trainer(*clip_, AdaptiveConfig(), AllFrames(), 7);
  double first = 0, last = 0;
  for (int i = 0; i < 300; ++i) {
    const StepStats stats = trainer.Step();
    ASSERT_TRUE(std::isfinite(stats.loss)) << "iteration " << i;
    ASSERT_GT(stats.guided_rays, 0) << "iteration " << i;
    if (i < 10) first += stats.psnr / 10;
    if (i >= 290) last += stats.psnr / 10;
  }
  EXPECT_GT(last, first + 6.0) << "PSNR went from " << first << " to " << last;
  EXPECT_GT(last, 20.0);
  EXPECT_TRUE(trainer.uncertainty_map().ready());
}

TEST_F(AdaptiveTrainingTest, SwitchedOffMeansNoGuidedRays) {
  TrainConfig config = AdaptiveConfig();
  config.adaptive_sampling = false;
  Trainer trainer(*clip_, config, AllFrames(), 7);
  for (int i = 0; i < 3; ++i) EXPECT_EQ(trainer.Step().guided_rays, 0);
  EXPECT_EQ(trainer.uncertainty_map().iteration(), -1);
}

TEST_F(AdaptiveTrainingTest, FixedSeedRepeatsAndCheckpointResumes) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  std::vector<double> a, b;
  for (auto* losses : {&a, &b}) {
    Trainer trainer(*clip_, AdaptiveConfig(), AllFrames(), 11);
    for (int i = 0; i < 10; ++i) losses->push_back(trainer.Step().loss);
  }
  EXPECT_EQ(a, b);

  Trainer original(*clip_, AdaptiveConfig(), AllFrames(), 3);
  for (int i = 0; i < 10; ++i) original.Step();  // the map was refreshed at 0 and 7
  std::stringstream state;
  original.Save(state);
  const std::vector<float> saved_scores = original.uncertainty_map().scores();
  std::vector<double> expected, resumed;
  for (int i = 0; i < 10; ++i) expected.push_back(original.Step().loss);
  Trainer restored(*clip_, AdaptiveConfig(), AllFrames(), 3);
  restored.Load(state);
  EXPECT_EQ(restored.uncertainty_map().iteration(), 7);
  EXPECT_EQ(restored.uncertainty_map().scores(), saved_scores);
  for (int i = 0; i < 10; ++i) resumed.push_back(restored.Step().loss);
  for (int i = 0; i < 10; ++i)
    EXPECT_NEAR(resumed[i], expected[i], 1e-5 * std::abs(expected[i])) << "step " << i;
}

}  // namespace
}  // namespace endorecon::train
