// A whole training step on the GPU against the CPU's with the same seed (the same rays, samples and
// masks: the per-ray bodies and the field's per-sample math are the same functions), a GPU run
// resumed on the CPU from its checkpoint, and a short GPU reconstruction of the demo clip reaching the
// CPU preset's 120 s held-out PSNR. Skipped without a GPU.
#include "worker/engine/cuda/device_step.h"

#include <gtest/gtest.h>

#include <cmath>
#include <sstream>
#include <vector>

#include "tests/unit/object_clip.h"
#include "tests/unit/temp_dir.h"
#include "worker/engine/cuda/device.h"
#include "worker/engine/reconstruct.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/synthetic_clip.h"
#include "worker/engine/train/scene_fit.h"
#include "worker/engine/train/trainer.h"

namespace endorecon::cuda {
namespace {

class DeviceStepTest : public ::testing::Test {
 protected:
  void SetUp() override {
    if (DeviceCount() == 0) GTEST_SKIP() << "no CUDA device: " << ListDevices().problem;
    scene::SynthOptions synth;
    synth.frames = 8;
    synth.width = 48;
    synth.height = 40;
    scene::WriteSyntheticClip(synth, dir_ / "clip");
    clip_ = scene::LoadClip(dir_ / "clip");
    config_ = train::TrainConfig::Preset("cpu");
    config_.rays_per_batch = 256;
    config_.iterations = 100;
    train::FitToScene(clip_, config_);
  }
  std::vector<int> Frames() const {
    std::vector<int> frames(clip_.frame_count());
    for (int f = 0; f < clip_.frame_count(); ++f) frames[f] = f;
    return frames;
  }

  testing::TempDir dir_{"device-step"};
  scene::Clip clip_;
  train::TrainConfig config_;
};

double MaxRelative(const field::Field& a, const field::Field& b) {
  double worst = 0;
  const auto ab = a.Blocks();
  const auto bb = b.Blocks();
  for (std::size_t k = 0; k < ab.size(); ++k) {
    double diff = 0, scale = 1e-3;
    for (std::size_t i = 0; i < ab[k].size; ++i) {
      diff = std::fmax(diff, std::fabs(double(ab[k].value[i]) - bb[k].value[i]));
      scale = std::fmax(scale, std::fabs(double(bb[k].value[i])));
    }
    worst = std::fmax(worst, diff / scale);
  }
  return worst;
}

TEST_F(DeviceStepTest, AStepOnTheGpuIsTheCpuStep) {
  train::Trainer cpu(clip_, config_, Frames(), 11);
  train::Trainer gpu(clip_, config_, Frames(), 11, DeviceStepFactory(0));
  EXPECT_EQ(cpu.device(), "cpu");
  EXPECT_EQ(gpu.device().rfind("cuda:0", 0), 0u);
  for (int i = 0; i < 3; ++i) {
    const train::StepStats a = cpu.Step(0.01 * i);
    const train::StepStats b = gpu.Step(0.01 * i);
    EXPECT_NEAR(b.loss, a.loss, 1e-4 * std::fabs(a.loss)) << "step " << i;
    EXPECT_EQ(b.samples, a.samples);
  }
  gpu.SyncField();
  // Three Adam updates from gradients that agree to float rounding.
  EXPECT_LT(MaxRelative(gpu.field(), cpu.field()), 1e-3);
}

// An object in front of a backdrop with a learned background: the rays' background gradients reach
// the same parameters on the GPU (atomic adds) as on the CPU (partials in task order).
TEST(DeviceStepBackground, ALearnedBackgroundStepOnTheGpuIsTheCpuStep) {
  if (DeviceCount() == 0) GTEST_SKIP() << "no CUDA device: " << ListDevices().problem;
  testing::TempDir dir("device-backdrop");
  const scene::Clip clip = testing::ObjectClip(dir.path(), 6, 24, /*backdrop=*/true);
  train::TrainConfig config = train::TrainConfig::Preset("cpu");
  config.rays_per_batch = 256;
  config.iterations = 100;
  config.background = "learned";
  train::FitToScene(clip, config);
  const std::vector<int> frames = {0, 1, 2, 3, 4, 5};
  train::Trainer cpu(clip, config, frames, 11);
  train::Trainer gpu(clip, config, frames, 11, DeviceStepFactory(0));
  for (int i = 0; i < 3; ++i) {
    const train::StepStats a = cpu.Step(0.01 * i);
    const train::StepStats b = gpu.Step(0.01 * i);
    EXPECT_NEAR(b.loss, a.loss, 1e-4 * std::fabs(a.loss)) << "step " << i;
  }
  gpu.SyncField();
  ASSERT_EQ(cpu.field().Blocks().back().name, "background");
  EXPECT_LT(MaxRelative(gpu.field(), cpu.field()), 1e-3);
}

TEST_F(DeviceStepTest, AGpuCheckpointResumesOnTheCpu) {
  train::Trainer gpu(clip_, config_, Frames(), 5, DeviceStepFactory(0));
  for (int i = 0; i < 20; ++i) gpu.Step();
  std::stringstream state;
  gpu.Save(state);
  train::Trainer cpu(clip_, config_, Frames(), 5);
  cpu.Load(state);
  EXPECT_EQ(cpu.iteration(), 20);
  const train::StepStats next_gpu = gpu.Step();
  const train::StepStats next_cpu = cpu.Step();
  EXPECT_NEAR(next_cpu.loss, next_gpu.loss, 1e-3 * std::fabs(next_gpu.loss));
}

TEST(DeviceReconstruct, TheDemoClipOnTheGpuReachesTheCpuPresets120sPsnr) {
  if (DeviceCount() == 0) GTEST_SKIP() << "no CUDA device: " << ListDevices().problem;
  testing::TempDir dir("gpu-demo");
  scene::WriteSyntheticClip(scene::SynthOptions{}, dir / "clip");
  ReconstructOptions options;
  options.clip_dir = (dir / "clip").string();
  options.out_dir = (dir / "out").string();
  options.device = "cuda:0";
  options.time_budget_s = 60;
  const ReconstructSummary summary = Reconstruct(options, {});
  EXPECT_EQ(summary.device.rfind("cuda:0", 0), 0u);
  // The CPU preset's held-out tissue PSNR after 120 s on 2 cores on today's demo clip, which carries
  // camera noise (docs/benchmarks.md, 2026-12-02: 32.72-32.83 dB; the noise caps any render at
  // 34.72 dB against its images). The 36.2 dB here before was the noise-free clip's.
  EXPECT_GE(summary.heldout_psnr, 32.7);
}

}  // namespace
}  // namespace endorecon::cuda
