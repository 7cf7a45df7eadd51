// Frames rendered on the GPU against the CPU's from the same field: colour, depth and opacity with
// empty-space skipping, the uncertainty maps of K dropout passes (the same chunks, so the same masks),
// a learned background, and a run's renders reading its GPU steps' copy of the field. The fields are
// trained a little first, so the renders have structure (a field at its initial values renders nearly
// flat). The per-ray bodies (frame_math.h) and the field's per-sample math are the same functions on
// both sides; what differs is float rounding (fused multiply-adds, the order of the GPU's reductions),
// which the adaptive samples can move a little. The clip is made in memory (scripts/gpu-check carries
// this binary). Skipped without a GPU.
#include "worker/engine/cuda/device_render.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <string>
#include <utility>
#include <vector>

#include "tests/cuda/small_clip.h"
#include "worker/engine/cuda/device.h"
#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/run_config.h"
#include "worker/engine/train/render_settings.h"
#include "worker/engine/train/scene_fit.h"
#include "worker/engine/train/trainer.h"

namespace endorecon::cuda {
namespace {

double MaxAbsDifference(const std::vector<float>& a, const std::vector<float>& b) {
  double worst = 0;
  for (std::size_t i = 0; i < a.size(); ++i) worst = std::max(worst, std::fabs(double(a[i]) - b[i]));
  return worst;
}

double MeanAbs(const std::vector<float>& a) {
  double sum = 0;
  for (float v : a) sum += std::fabs(v);
  return a.empty() ? 0 : sum / a.size();
}

double MeanAbsDifference(const std::vector<float>& a, const std::vector<float>& b) {
  double sum = 0;
  for (std::size_t i = 0; i < a.size(); ++i) sum += std::fabs(double(a[i]) - b[i]);
  return a.empty() ? 0 : sum / a.size();
}

class DeviceRenderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (DeviceCount() == 0) GTEST_SKIP() << "no CUDA device: " << ListDevices().problem;
    clip_ = SmallClip();
  }

  // A CPU trainer after `steps` steps with `background` ("auto" or "learned").
  std::unique_ptr<train::Trainer> Trained(const std::string& background, int steps) {
    config_ = train::TrainConfig::Preset("cpu");
    config_.rays_per_batch = 256;
    config_.iterations = steps;
    config_.background = background;
    std::vector<int> frames(clip_.frame_count());
    std::iota(frames.begin(), frames.end(), 0);
    train::FitToScene(clip_, config_, frames);
    auto trainer = std::make_unique<train::Trainer>(clip_, config_, frames, 7);
    for (int i = 0; i < steps; ++i) trainer->Step(double(i) / steps);
    return trainer;
  }

  // The frame of clip frame f from both backends.
  std::pair<render::RenderedFrame, render::RenderedFrame> Both(train::Trainer& trainer,
                                                               const render::FrameRenderSettings& settings,
                                                               int f) {
    render::FrameRenderer cpu(trainer.field(), trainer.box(), settings);
    render::FrameRenderer gpu(trainer.field(), trainer.box(), settings, DeviceRenderFactory(0));
    EXPECT_EQ(gpu.device().rfind("cuda:0", 0), 0u);
    cpu.SetOccupancy(&trainer.occupancy());
    gpu.SetOccupancy(&trainer.occupancy());
    return {cpu.Render(clip_.cameras[f], clip_.times[f]), gpu.Render(clip_.cameras[f], clip_.times[f])};
  }

  scene::Clip clip_;
  train::TrainConfig config_;
};

TEST_F(DeviceRenderTest, AFrameRenderedOnTheGpuIsTheCpusFrame) {
  auto trainer = Trained("auto", 150);
  ASSERT_FALSE(trainer->occupancy().empty());
  auto settings = train::EvalRenderSettings(config_, clip_.near, clip_.far);
  settings.rays_per_chunk = 512;  // several chunks per frame
  const auto [cpu, gpu] = Both(*trainer, settings, 3);
  ASSERT_EQ(gpu.rgb.size(), cpu.rgb.size());
  EXPECT_TRUE(gpu.uncertainty.empty());
  EXPECT_LT(MaxAbsDifference(gpu.rgb, cpu.rgb), 0.02);
  EXPECT_LT(MeanAbsDifference(gpu.rgb, cpu.rgb), 1e-3);
  EXPECT_LT(MeanAbsDifference(gpu.depth, cpu.depth), 1e-3 * (clip_.far - clip_.near));
  EXPECT_LT(MeanAbsDifference(gpu.opacity, cpu.opacity), 1e-3);
}

TEST_F(DeviceRenderTest, UncertaintyMapsOnTheGpuAreTheCpus) {
  auto trainer = Trained("auto", 150);
  const auto settings = train::UncertaintyRenderSettings(config_, clip_.near, clip_.far, 5);
  ASSERT_GT(settings.mc_passes, 1);
  const auto [cpu, gpu] = Both(*trainer, settings, 5);
  ASSERT_EQ(gpu.uncertainty.size(), cpu.uncertainty.size());
  EXPECT_LT(MeanAbsDifference(gpu.rgb, cpu.rgb), 1e-3);
  // The same masks: the maps agree to rounding, not merely in distribution.
  EXPECT_GT(MeanAbs(cpu.epistemic), 0.0);
  EXPECT_LT(MeanAbsDifference(gpu.uncertainty, cpu.uncertainty), 1e-2 * MeanAbs(cpu.uncertainty));
  EXPECT_LT(MeanAbsDifference(gpu.aleatoric, cpu.aleatoric), 1e-2 * MeanAbs(cpu.aleatoric));
  EXPECT_LT(MeanAbsDifference(gpu.epistemic, cpu.epistemic), 1e-2 * MeanAbs(cpu.epistemic));
}

// A run's renders share the GPU steps' copy of the field (run_config.h BackendsFor): they see the
// parameters the steps wrote without a pull, as the CPU sees them after one.
TEST_F(DeviceRenderTest, ARunsRendersSeeWhatItsGpuStepsWrote) {
  config_ = train::TrainConfig::Preset("cpu");
  config_.rays_per_batch = 256;
  config_.iterations = 100;
  std::vector<int> frames(clip_.frame_count());
  std::iota(frames.begin(), frames.end(), 0);
  train::FitToScene(clip_, config_, frames);
  const DeviceBackends gpu = BackendsFor("cuda:0");
  train::Trainer trainer(clip_, config_, frames, 3, gpu.step, gpu.render);
  const auto settings = train::EvalRenderSettings(config_, clip_.near, clip_.far);
  render::FrameRenderer shared(trainer.field(), trainer.box(), settings, gpu.render);
  for (int i = 0; i < 100; ++i) trainer.Step(0.01 * i);
  const render::RenderedFrame seen = shared.Render(clip_.cameras[4], clip_.times[4]);  // no pull before
  trainer.SyncField();
  render::FrameRenderer cpu(trainer.field(), trainer.box(), settings);
  const render::RenderedFrame host = cpu.Render(clip_.cameras[4], clip_.times[4]);
  EXPECT_LT(MeanAbsDifference(seen.rgb, host.rgb), 1e-3);
}

TEST_F(DeviceRenderTest, ALearnedBackgroundIsRenderedOnTheGpuAsOnTheCpu) {
  auto trainer = Trained("learned", 100);
  ASSERT_NE(trainer->field().background(), nullptr);
  const auto settings = train::EvalRenderSettings(config_, clip_.near, clip_.far);
  const auto [cpu, gpu] = Both(*trainer, settings, 2);
  EXPECT_LT(MeanAbsDifference(gpu.rgb, cpu.rgb), 1e-3);
}

}  // namespace
}  // namespace endorecon::cuda
