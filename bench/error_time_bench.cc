// Error against run time on the synthetic demo clip (48 frames, 160 x 128, every 8th frame held
// out), or on any clip given with --clip: held-out tissue PSNR and depth error at fixed training
// times, beside the 2D baseline of averaging the two neighbouring frames (t-1, t+1) of each held-out
// frame, and the training frames' PSNR at the end.
//   error_time_bench [--budget SECONDS] [--preset cpu|paper] [--out DIR] [--override JSON] [--clip DIR]
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "worker/engine/eval/clip_evaluator.h"
#include "worker/engine/eval/psnr.h"
#include "worker/engine/reconstruct.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/synthetic_clip.h"

namespace {

using nlohmann::literals::operator""_json_pointer;

double NeighbourBaselinePsnr(const endorecon::scene::Clip& clip, const std::vector<int>& heldout) {
  double sum = 0;
  for (int f : heldout) {
    const int a = std::max(0, f - 1), b = std::min(clip.frame_count() - 1, f + 1);
    std::vector<float> average(clip.rgb[f].size());
    for (std::size_t i = 0; i < average.size(); ++i) {
      average[i] = (float(clip.rgb[a][i]) + float(clip.rgb[b][i])) / (2.0f * 255.0f);
    }
    sum += endorecon::eval::Psnr(average, clip.rgb[f], endorecon::eval::EvaluationMask(clip, f), clip.width,
                                 clip.height);
  }
  return sum / double(heldout.size());
}

}  // namespace

int main(int argc, char** argv) {
  double budget = 300;
  std::string preset = "cpu", out = "/tmp/endorecon-error-time-bench", overrides = "{}", clip_dir;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string flag = argv[i];
    if (flag == "--budget") budget = std::stod(argv[i + 1]);
    if (flag == "--preset") preset = argv[i + 1];
    if (flag == "--out") out = argv[i + 1];
    if (flag == "--override") overrides = argv[i + 1];
    if (flag == "--clip") clip_dir = argv[i + 1];
  }
  namespace fs = std::filesystem;
  fs::remove_all(out);
  if (clip_dir.empty()) {
    clip_dir = (fs::path(out) / "clip").string();
    endorecon::scene::WriteSyntheticClip(endorecon::scene::SynthOptions{}, clip_dir);
  }
  // Every held-out frame on the curve, a point every 15 s; --override JSON adds config keys (a variant).
  nlohmann::json config = nlohmann::json::parse(overrides);
  config["curve_interval_s"] = 15.0;
  config["curve_frames"] = 6;

  endorecon::ReconstructOptions options;
  options.clip_dir = clip_dir;
  options.out_dir = (fs::path(out) / "result").string();
  options.config = config;
  options.preset = preset;
  options.holdout = 8;
  options.iterations = 1000000;
  options.time_budget_s = budget;
  endorecon::Reconstruct(options, {});

  const auto clip = endorecon::scene::LoadClip(options.clip_dir);
  std::ifstream in(fs::path(options.out_dir) / "metrics.json");
  const auto metrics = nlohmann::json::parse(in);
  const auto heldout = metrics["heldout"]["frames"].get<std::vector<int>>();
  std::printf("neighbour-average baseline, held-out tissue PSNR: %.2f dB\n",
              NeighbourBaselinePsnr(clip, heldout));
  std::printf("%10s %10s %14s %22s\n", "seconds", "iteration", "held-out PSNR", "depth RMSE / range");
  for (const auto& point : metrics["curve"]) {
    std::printf("%10.1f %10d %14.2f %22.4f\n", point["seconds"].get<double>(), point["iteration"].get<int>(),
                point.value("heldout_psnr", -1.0), point.value("heldout_depth_rmse_relative", -1.0));
  }
  const auto depth = "/heldout/depth/rmse_relative/mean"_json_pointer;
  std::printf("final (all held-out frames): PSNR %.2f dB, depth RMSE / range %.4f, %.2f M samples/s\n",
              metrics["heldout"]["image"]["psnr_tissue"]["mean"].get<double>(),
              metrics.contains(depth) ? metrics[depth].get<double>() : -1.0,
              metrics["samples_per_second"].get<double>() / 1e6);
  // The training frames rendered in full (the evaluation renders the rest at reduced cost).
  const auto train_full = "/evaluation/train_psnr_tissue/full/mean"_json_pointer;
  if (metrics.contains(train_full)) {
    std::printf("training frames rendered in full: PSNR %.2f dB (%d frames)\n", metrics[train_full].get<double>(),
                metrics["evaluation"]["train_psnr_tissue"]["full"]["count"].get<int>());
  }
  return 0;
}
