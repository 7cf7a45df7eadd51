// Novel viewpoints: reconstruct a stereo synthetic clip from the LEFT eye only, then render the
// right eye's cameras (never seen in training) and measure PSNR against the right images.
// The clip has no tool (the right eye has no masks) and the columns the left eye cannot see (the
// right eye's outer edge, within the largest disparity f * baseline / near) are left out.
//   novel_view_bench [--budget SECONDS] [--out DIR]
#include <CLI/CLI.hpp>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>

#include "worker/engine/eval/psnr.h"
#include "worker/engine/reconstruct.h"
#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/synthetic_clip.h"
#include "worker/engine/train/checkpoint.h"
#include "worker/engine/train/render_settings.h"
#include "worker/engine/train/trainer.h"

int main(int argc, char** argv) {
  double budget = 120;
  std::string out = "/tmp/endorecon-novel-view-bench";
  CLI::App app{"novel_view_bench: the other eye rendered from a model trained on one"};
  app.add_option("--budget", budget, "the run's time budget, seconds")->capture_default_str();
  app.add_option("--out", out, "scratch folder (emptied first)")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  namespace fs = std::filesystem;
  fs::remove_all(out);
  endorecon::scene::SynthOptions synth;
  synth.stereo = true;
  synth.tool = false;
  endorecon::scene::WriteSyntheticClip(synth, fs::path(out) / "clip");

  endorecon::ReconstructOptions options;
  options.clip_dir = (fs::path(out) / "clip").string();
  options.out_dir = (fs::path(out) / "result").string();
  options.holdout = 0;
  options.iterations = 1000000;
  options.time_budget_s = budget;
  const auto summary = endorecon::Reconstruct(options, {});

  const auto clip = endorecon::scene::LoadClip(options.clip_dir);
  const auto model = endorecon::train::ReadModel(fs::path(options.out_dir) / "model" / "model.bin");
  // The results' evaluation settings, without the dropout passes: colour only.
  auto settings = endorecon::train::UncertaintyRenderSettings(model.config, model.near, model.far, 0);
  settings.mc_passes = 0;
  endorecon::render::FrameRenderer renderer(*model.field, model.box, settings);
  const auto occupancy = endorecon::train::BuildOccupancy(*model.field, model.config);
  renderer.SetOccupancy(&occupancy);

  // The right camera sits at +baseline along x: it sees up to f * baseline / near pixels past the
  // left frame's right edge. Mask those columns as "not seen by the left eye" (1 = excluded).
  const auto& left = clip.cameras[0];
  const auto& right = clip.right_cameras[0];
  const double baseline = (right.c2w.col(3) - left.c2w.col(3)).norm();
  const int hidden = std::min(clip.width, int(std::ceil(left.fx * baseline / std::max(clip.near, 1e-6))));
  std::vector<std::uint8_t> unseen(std::size_t(clip.width) * clip.height, 0);
  for (int y = 0; y < clip.height; ++y) {
    for (int x = clip.width - hidden; x < clip.width; ++x) unseen[std::size_t(y) * clip.width + x] = 1;
  }
  double right_sum = 0, left_sum = 0;
  for (int f = 0; f < clip.frame_count(); ++f) {
    const auto view = renderer.Render(clip.right_cameras[f], clip.times[f]);
    right_sum += endorecon::eval::Psnr(view.rgb, clip.right_rgb[f], unseen, clip.width, clip.height);
    const auto same = renderer.Render(clip.cameras[f], clip.times[f]);
    left_sum += endorecon::eval::Psnr(same.rgb, clip.rgb[f], unseen, clip.width, clip.height);
  }
  std::printf(
      "trained %d iterations in %.0f s on the left eye (%d frames, %dx%d); %d right-edge columns excluded\n",
      summary.iterations, summary.train_seconds, clip.frame_count(), clip.width, clip.height, hidden);
  std::printf("right eye (novel view) PSNR: %.2f dB; left eye (training views) PSNR: %.2f dB\n",
              right_sum / clip.frame_count(), left_sum / clip.frame_count());
  return 0;
}
