// Error against run time on the synthetic demo clip (48 frames, 160 x 128, every 8th frame held
// out), or on any clip given with --clip: held-out tissue PSNR and depth error at fixed training
// times, beside the 2D baseline of averaging the two neighbouring frames (t-1, t+1) of each held-out
// frame, and the training frames' PSNR at the end.
//   error_time_bench [--budget SECONDS] [--preset cpu|paper] [--out DIR] [--override JSON] [--clip DIR]
#include <CLI/CLI.hpp>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "worker/engine/eval/clip_evaluator.h"
#include "worker/engine/eval/evaluation_mask.h"
#include "worker/engine/eval/gain_fit.h"
#include "worker/engine/eval/psnr.h"
#include "worker/engine/reconstruct.h"
#include "worker/engine/run_config.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/synthetic_clip.h"

namespace {

using nlohmann::literals::operator""_json_pointer;

// Against `reference`: the clip's images, or its noise-free truth; `gain_fitted`: after the frame's
// exposure is fitted, as the evaluation's image_gain_fitted (eval/gain_fit.h).
double NeighbourBaselinePsnr(const endorecon::scene::Clip& clip, const std::vector<int>& heldout,
                             const std::vector<std::vector<std::uint8_t>>& reference,
                             bool gain_fitted = false) {
  double sum = 0;
  for (int f : heldout) {
    // The frames before and after; at either end of the clip the one neighbour it has (never the
    // held-out frame itself, which the stand-in is to predict).
    const int last = clip.frame_count() - 1;
    const int a = f > 0 ? f - 1 : 1, b = f < last ? f + 1 : last - 1;
    std::vector<float> average(clip.rgb[f].size());
    for (std::size_t i = 0; i < average.size(); ++i) {
      average[i] = (float(clip.rgb[a][i]) + float(clip.rgb[b][i])) / (2.0f * 255.0f);
    }
    const auto& mask = endorecon::eval::EvaluationMask(clip, f);
    if (gain_fitted)
      average = endorecon::eval::FitGain(average, reference[f], mask, clip.width, clip.height).rgb;
    sum += endorecon::eval::Psnr(average, reference[f], mask, clip.width, clip.height);
  }
  return sum / double(heldout.size());
}

}  // namespace

int main(int argc, char** argv) {
  double budget = 300;
  std::string preset = "cpu", out = "/tmp/endorecon-error-time-bench", overrides = "{}", clip_dir;
  CLI::App app{"error_time_bench: held-out error against run time, beside the neighbour-average stand-in"};
  app.add_option("--budget", budget, "the run's time budget, seconds")->capture_default_str();
  app.add_option("--preset", preset, "training preset")->capture_default_str();
  app.add_option("--out", out, "scratch folder (emptied first)")->capture_default_str();
  app.add_option("--override", overrides, "training keys over the preset, JSON")->capture_default_str();
  app.add_option("--clip", clip_dir, "clip folder (default: the demo clip, written into --out)");
  CLI11_PARSE(app, argc, argv);
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
  const auto clip = endorecon::scene::LoadClip(options.clip_dir);
  if (endorecon::SplitFrames(clip.frame_count(), options.holdout).heldout.empty()) {
    std::fprintf(stderr, "%s: %d frames hold none out at every %dth: the bench needs at least %d frames\n",
                 clip_dir.c_str(), clip.frame_count(), options.holdout, options.holdout);
    return 2;
  }
  endorecon::Reconstruct(options, {});

  std::ifstream in(fs::path(options.out_dir) / "metrics.json");
  const auto metrics = nlohmann::json::parse(in);
  const auto heldout = metrics["heldout"]["frames"].get<std::vector<int>>();
  std::printf("neighbour-average baseline, held-out tissue PSNR: %.2f dB\n",
              NeighbourBaselinePsnr(clip, heldout, clip.rgb));
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
    std::printf("training frames rendered in full: PSNR %.2f dB (%d frames)\n",
                metrics[train_full].get<double>(),
                metrics["evaluation"]["train_psnr_tissue"]["full"]["count"].get<int>());
  }
  std::printf(
      "with each held-out frame's exposure fitted (image_gain_fitted): PSNR %.2f dB (neighbour average %.2f "
      "dB)\n",
      metrics["heldout"]["image_gain_fitted"]["psnr_tissue"]["mean"].get<double>(),
      NeighbourBaselinePsnr(clip, heldout, clip.rgb, true));
  // A synthetic clip's camera noise bounds the PSNR against its images; the same against its truth.
  if (!clip.gt_rgb.empty()) {
    const auto mean = [&](const char* key) {
      return metrics["heldout"][key]["psnr_tissue"]["mean"].get<double>();
    };
    std::printf("against the noise-free truth: held-out PSNR %.2f dB (neighbour average %.2f dB)\n",
                mean("image_noise_free"), NeighbourBaselinePsnr(clip, heldout, clip.gt_rgb));
    std::printf("  exposure fitted: held-out PSNR %.2f dB (neighbour average %.2f dB)\n",
                mean("image_noise_free_gain_fitted"),
                NeighbourBaselinePsnr(clip, heldout, clip.gt_rgb, true));
    const auto truth_full = "/evaluation/train_psnr_tissue_noise_free/full/mean"_json_pointer;
    if (metrics.contains(truth_full))
      std::printf("  training frames rendered in full: PSNR %.2f dB\n", metrics[truth_full].get<double>());
    double noise = 0;
    for (int f = 0; f < clip.frame_count(); ++f) {
      std::vector<float> truth(clip.gt_rgb[f].begin(), clip.gt_rgb[f].end());
      for (float& v : truth) v /= 255.0f;
      noise += endorecon::eval::Psnr(truth, clip.rgb[f], endorecon::eval::EvaluationMask(clip, f), clip.width,
                                     clip.height);
    }
    std::printf("the truth against the images (the camera noise's bound): %.2f dB\n",
                noise / clip.frame_count());
  }
  return 0;
}
