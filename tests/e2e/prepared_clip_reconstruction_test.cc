// Issue 16's reconstruction target, small: the synthetic stereo pair prepared with --rectified (the
// same images, depth by stereo matching instead of the generator's own) reconstructs within 1 dB
// of held-out PSNR of the synthetic clip itself, after the same short training (400 iterations). The properly
// sized measurement is bench/prepare_bench --reconstruct (docs/benchmarks.md).
#include <gtest/gtest.h>

#include <cstdio>
#include <nlohmann/json.hpp>

#include "tests/unit/temp_dir.h"
#include "worker/engine/reconstruct.h"
#include "worker/engine/scene/synthetic_clip.h"
#include "worker/prepare/prepare_clip.h"

namespace endorecon {
namespace {

// The same short run for both clips: a fixed number of iterations (not seconds, so a busy machine
// changes nothing), evaluation without the uncertainty passes (not measured here).
double HeldOutPsnr(const std::filesystem::path& clip, const std::filesystem::path& out) {
  ReconstructOptions options;
  options.clip_dir = clip.string();
  options.out_dir = out.string();
  options.config = {{"rays_per_batch", 512},
                    {"mc_passes", 0},
                    {"curve_interval_s", 1000},
                    {"eval_coarse_samples", 32},
                    {"eval_fine_samples", 32}};
  options.iterations = 400;
  options.holdout = 4;
  return Reconstruct(options, {}).heldout_psnr;
}

TEST(PreparedClipReconstructionTest, StereoDepthReconstructsAsWellAsTheGeneratorsOwn) {
  testing::TempDir dir("prepared-reconstruction");
  scene::SynthOptions synth;
  synth.frames = 16;
  synth.width = 160;
  synth.height = 128;
  synth.stereo = true;
  scene::WriteSyntheticClip(synth, dir / "synth");

  prepare::PrepareOptions options;
  options.recording = {
      prepare::StereoLayout::kTwoSources, dir / "synth/images", dir / "synth/images_right", {}};
  options.rectified = true;
  options.focal = scene::SyntheticScene(synth).LeftCamera().fx;
  options.baseline = 5;
  options.masks = dir / "synth/masks";
  options.out = dir / "prepared";
  const prepare::PrepareSummary summary = prepare::PrepareClip(options);
  EXPECT_GT(summary.depth_coverage, 0.8);

  const double own = HeldOutPsnr(dir / "synth", dir / "own");
  const double prepared = HeldOutPsnr(dir / "prepared", dir / "stereo");
  std::printf("held-out PSNR: generator's depth %.2f dB, stereo depth %.2f dB\n", own, prepared);
  EXPECT_GT(own, 20);
  EXPECT_GE(prepared, own - 1.0) << "generator's depth " << own << " dB, stereo depth " << prepared << " dB";
}

}  // namespace
}  // namespace endorecon
