// A GPU run on a clip read from files: a short GPU reconstruction of the demo clip reaching the CPU
// preset's 120 s held-out PSNR, which writes its results (images, video) through OpenCV, whose
// libraries do not fit what travels to a bare GPU machine; so it builds into its own binary
// (endorecon_cuda_file_tests), not the bundle of scripts/gpu-check. Skipped without a GPU.
#include <gtest/gtest.h>

#include "tests/unit/temp_dir.h"
#include "worker/engine/cuda/device.h"
#include "worker/engine/reconstruct.h"
#include "worker/engine/scene/synthetic_clip.h"

namespace endorecon::cuda {
namespace {

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
