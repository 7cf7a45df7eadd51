// GPU runs on clips read from files: a learned-background step on an object capture against the
// CPU's, and a short GPU reconstruction of the demo clip reaching the CPU preset's 120 s held-out
// PSNR. They read and write images and video through OpenCV, whose libraries do not fit what
// travels to a bare GPU machine, so they build into their own binary (endorecon_cuda_file_tests),
// not the bundle of scripts/gpu-check. Skipped without a GPU.
#include <gtest/gtest.h>

#include <vector>

#include "tests/cuda/field_difference.h"
#include "tests/unit/object_clip.h"
#include "tests/unit/temp_dir.h"
#include "worker/engine/cuda/device.h"
#include "worker/engine/cuda/device_step.h"
#include "worker/engine/reconstruct.h"
#include "worker/engine/scene/synthetic_clip.h"
#include "worker/engine/train/scene_fit.h"
#include "worker/engine/train/trainer.h"

namespace endorecon::cuda {
namespace {

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
