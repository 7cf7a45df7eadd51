#include "worker/engine/reconstruct.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/global_control.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <numeric>

#include "common/error.h"
#include "worker/engine/eval/clip_evaluator.h"
#include "worker/engine/eval/curve_plot.h"
#include "worker/engine/eval/depth_error.h"
#include "worker/engine/eval/image_metrics.h"
#include "worker/engine/eval/report.h"
#include "worker/engine/eval/summary.h"
#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/train/checkpoint.h"
#include "worker/engine/train/scene_fit.h"
#include "worker/engine/train/trainer.h"

namespace endorecon {
namespace {

using nlohmann::literals::operator""_json_pointer;

using Clock = std::chrono::steady_clock;
namespace fs = std::filesystem;

// The preset (or, on resume, the checkpoint's configuration) with the config file and options over it.
train::TrainConfig ResolveConfig(const ReconstructOptions& options) {
  train::TrainConfig config = options.resume_from.empty() ? train::TrainConfig::Preset(options.preset)
                                                          : train::ReadCheckpointConfig(options.resume_from);
  if (!options.config_file.empty()) {
    std::ifstream in(options.config_file);
    if (!in) Fail(ErrorCode::kNotFound, "cannot read config file " + options.config_file);
    nlohmann::json json;
    try {
      json = nlohmann::json::parse(in);
    } catch (const nlohmann::json::exception& e) {
      FailInvalid(options.config_file + ": not valid JSON: " + e.what());
    }
    train::ApplyJson(json, config);
  }
  if (options.iterations > 0) config.iterations = options.iterations;
  if (options.holdout >= 0) config.holdout = options.holdout;
  return config;
}

struct Split {
  std::vector<int> train, heldout;
};

// Every K-th frame (K-1, 2K-1, ...) is held out; frame 0, which fixes the canonical space, never is.
Split MakeSplit(int frames, int holdout) {
  Split split;
  for (int f = 0; f < frames; ++f) {
    (holdout > 1 && (f + 1) % holdout == 0 ? split.heldout : split.train).push_back(f);
  }
  return split;
}

// Held-out PSNR on a fixed subset of pixels of a few held-out frames: cheap enough to measure
// every few seconds for the error-against-time curve.
class CurveProbe {
 public:
  CurveProbe(const scene::Clip& clip, const std::vector<int>& heldout, int max_frames) : clip_(clip) {
    const int step = std::max<int>(1, int(heldout.size()) / std::max(1, max_frames));
    for (std::size_t i = 0; i < heldout.size() && int(frames_.size()) < max_frames; i += step) {
      frames_.push_back(heldout[i]);
    }
  }
  bool empty() const { return frames_.empty(); }

  struct Point {
    double psnr = 0;
    double depth_rmse = -1;  // relative to far - near; -1 without ground-truth depth
  };

  // Means over the probe frames where the value is defined (an all-tool frame has no tissue PSNR).
  Point Measure(render::FrameRenderer& renderer) const {
    std::vector<double> psnr, depth;
    for (int f : frames_) {
      const auto frame = renderer.Render(clip_.cameras[f], clip_.times[f]);
      const auto& mask = eval::EvaluationMask(clip_, f);
      psnr.push_back(
          eval::MeasureImage(frame.rgb, clip_.rgb[f], mask, clip_.width, clip_.height).psnr_tissue);
      if (!clip_.gt_depth.empty()) {
        depth.push_back(eval::MeasureDepth(frame.depth, clip_.gt_depth[f], mask, clip_.width, clip_.height,
                                           clip_.near, clip_.far)
                            .rmse_relative);
      }
    }
    Point point;
    point.psnr = eval::Summarise(psnr).mean;
    if (!depth.empty()) point.depth_rmse = eval::Summarise(depth).mean;
    return point;
  }

 private:
  const scene::Clip& clip_;
  std::vector<int> frames_;
};

Preview MakePreview(const render::RenderedFrame& frame, int index) {
  Preview preview;
  preview.kind = "rgb";
  preview.frame = index;
  preview.width = frame.width;
  preview.height = frame.height;
  preview.channels = 3;
  preview.pixels.resize(frame.rgb.size());
  for (std::size_t i = 0; i < frame.rgb.size(); ++i) {
    preview.pixels[i] = std::uint8_t(std::lround(std::clamp(frame.rgb[i], 0.0f, 1.0f) * 255.0f));
  }
  return preview;
}

// The total uncertainty as 8-bit grey, scaled by the preview's own largest value (a preview shows
// where the uncertainty is, not how large it is; the results' heat maps carry the clip-wide scale).
Preview MakeUncertaintyPreview(const render::RenderedFrame& frame, int index) {
  Preview preview;
  preview.kind = "uncertainty";
  preview.frame = index;
  preview.width = frame.width;
  preview.height = frame.height;
  preview.channels = 1;
  float top = 0;
  for (float v : frame.uncertainty) top = std::isfinite(v) ? std::max(top, v) : top;
  preview.pixels.resize(frame.uncertainty.size());
  for (std::size_t i = 0; i < frame.uncertainty.size(); ++i) {
    const float v = std::isfinite(frame.uncertainty[i]) && top > 0 ? frame.uncertainty[i] / top : 0.0f;
    preview.pixels[i] = std::uint8_t(std::lround(std::clamp(v, 0.0f, 1.0f) * 255.0f));
  }
  return preview;
}

render::FrameRenderSettings RenderSettings(const train::TrainConfig& config, double near, double far) {
  render::FrameRenderSettings settings;
  settings.near = near;
  settings.far = far;
  settings.coarse_samples = config.eval_coarse_samples;
  settings.fine_samples = config.eval_fine_samples;
  settings.floor = config.eval_floor;
  return settings;
}

}  // namespace

render::FrameRenderSettings UncertaintyRenderSettings(const train::TrainConfig& config, double near,
                                                      double far, std::uint64_t seed) {
  render::FrameRenderSettings settings = RenderSettings(config, near, far);
  settings.mc_passes = config.mc_passes;
  settings.color_weight = config.uncertainty_lambda;
  settings.variance_eps = config.variance_eps;
  settings.mc_seed = seed;
  return settings;
}

ReconstructSummary Reconstruct(const ReconstructOptions& options, const ReconstructHooks& hooks) {
  const int threads = options.threads > 0 ? options.threads : int(std::thread::hardware_concurrency());
  tbb::global_control threads_control(tbb::global_control::max_allowed_parallelism, std::max(1, threads));

  scene::LoadOptions load;
  load.force_static = options.force_static;
  const scene::Clip clip = scene::LoadClip(options.clip_dir, load);
  train::TrainConfig config = ResolveConfig(options);
  const Split split = MakeSplit(clip.frame_count(), config.holdout);
  const train::SceneFit fit = train::FitToScene(clip, config);
  const fs::path out_dir = options.out_dir;
  fs::create_directories(out_dir);
  {
    std::ofstream(out_dir / "config.json") << nlohmann::json{
        {"train", train::ToJson(config)},
        {"clip", options.clip_dir},
        {"seed", options.seed},
        {"time_budget_s", options.time_budget_s},
        {"threads", threads}}.dump(2);
  }

  train::Trainer trainer(clip, config, split.train, options.seed);
  train::CheckpointExtras extras;
  if (!options.resume_from.empty()) {
    extras = train::ReadCheckpointState(options.resume_from, trainer);
    spdlog::info("resumed from {} at iteration {}", options.resume_from, trainer.iteration());
  }
  spdlog::info("clip {}: {} frames {}x{}, {} train / {} held out; {}", clip.source, clip.frame_count(),
               clip.width, clip.height, split.train.size(), split.heldout.size(), trainer.field().Describe());

  render::FrameRenderer renderer(trainer.field(), trainer.box(), RenderSettings(config, clip.near, clip.far));
  // Both renderers skip what the trainer's occupancy grid says is empty (rebuilt during training and,
  // for the results, from the final field).
  renderer.SetOccupancy(&trainer.occupancy());
  render::FrameRenderer uncertainty_renderer(
      trainer.field(), trainer.box(), UncertaintyRenderSettings(config, clip.near, clip.far, options.seed));
  uncertainty_renderer.SetOccupancy(&trainer.occupancy());
  const CurveProbe probe(clip, split.heldout, config.curve_frames);
  const fs::path checkpoint_path = out_dir / "model" / "checkpoint.bin";

  ReconstructSummary summary;
  double train_seconds = extras.train_seconds;
  double next_curve = extras.curve.empty() ? 0.0 : train_seconds + config.curve_interval_s;
  auto last_progress = Clock::now(), last_preview = Clock::now(), last_checkpoint = Clock::now();
  double window_samples = 0, window_seconds = 0, samples_per_second = 0;
  double run_samples = 0, run_step_seconds = 0;  // this process's steps, for metrics.json
  Progress progress;
  progress.total_iterations = config.iterations;
  const auto add_curve_point = [&](const train::StepStats& stats) {
    nlohmann::json point = {{"seconds", train_seconds},
                            {"iteration", trainer.iteration()},
                            {"loss", stats.loss},
                            {"train_psnr", stats.psnr}};
    if (!probe.empty()) {
      const CurveProbe::Point measured = probe.Measure(renderer);
      progress.heldout_psnr = measured.psnr;
      progress.depth_rmse = measured.depth_rmse;
      point["heldout_psnr"] = measured.psnr;
      if (measured.depth_rmse >= 0) point["heldout_depth_rmse_relative"] = measured.depth_rmse;
    }
    extras.curve.push_back(point);
  };

  train::StepStats stats;
  while (trainer.iteration() < config.iterations) {
    if (options.time_budget_s > 0 && train_seconds >= options.time_budget_s) break;
    if (hooks.should_stop && hooks.should_stop()) {
      summary.cancelled = true;
      break;
    }
    const auto start = Clock::now();
    double schedule = double(trainer.iteration()) / std::max(1, config.iterations);
    if (options.time_budget_s > 0) schedule = std::max(schedule, train_seconds / options.time_budget_s);
    stats = trainer.Step(schedule);
    const double dt = std::chrono::duration<double>(Clock::now() - start).count();
    train_seconds += dt;
    window_samples += double(stats.samples);
    window_seconds += dt;
    run_samples += double(stats.samples);
    run_step_seconds += dt;
    if (train_seconds >= next_curve || trainer.iteration() == config.iterations) {
      add_curve_point(stats);
      next_curve = train_seconds + config.curve_interval_s;
    }
    const auto now = Clock::now();
    if (std::chrono::duration<double>(now - last_progress).count() >= hooks.progress_interval_s) {
      samples_per_second = window_samples / std::max(window_seconds, 1e-9);
      window_samples = window_seconds = 0;
      progress.iteration = trainer.iteration();
      progress.seconds = train_seconds;
      progress.loss = stats.loss;
      progress.train_psnr = stats.psnr;
      progress.samples_per_second = samples_per_second;
      const double per_iteration = train_seconds / std::max(1, trainer.iteration());
      double eta = (config.iterations - trainer.iteration()) * per_iteration;
      if (options.time_budget_s > 0) eta = std::min(eta, options.time_budget_s - train_seconds);
      progress.eta_s = std::max(0.0, eta);
      if (hooks.on_progress) hooks.on_progress(progress);
      last_progress = now;
    }
    if (hooks.on_preview &&
        std::chrono::duration<double>(now - last_preview).count() >= hooks.preview_interval_s) {
      const int f = split.heldout.empty() ? 0 : split.heldout.front();
      const auto frame = uncertainty_renderer.Render(fit.preview_camera(clip.cameras[f]), clip.times[f]);
      hooks.on_preview(MakePreview(frame, f));
      if (!frame.uncertainty.empty()) hooks.on_preview(MakeUncertaintyPreview(frame, f));
      last_preview = Clock::now();
    }
    if (std::chrono::duration<double>(now - last_checkpoint).count() >= hooks.checkpoint_interval_s) {
      extras.train_seconds = train_seconds;
      train::WriteCheckpoint(checkpoint_path, trainer, extras);
      if (hooks.on_checkpoint) hooks.on_checkpoint(checkpoint_path.string());
      last_checkpoint = Clock::now();
    }
  }
  if (extras.curve.empty() || extras.curve.back().at("iteration").get<int>() != trainer.iteration()) {
    add_curve_point(stats);
  }
  extras.train_seconds = train_seconds;
  train::WriteCheckpoint(checkpoint_path, trainer, extras);
  if (hooks.on_checkpoint) hooks.on_checkpoint(checkpoint_path.string());
  train::WriteModel(out_dir / "model" / "model.bin", config, trainer.box(), clip.near, clip.far,
                    trainer.field());

  summary.iterations = trainer.iteration();
  summary.train_seconds = train_seconds;
  summary.train_psnr = stats.psnr;
  nlohmann::json metrics;
  nlohmann::json left_out = fit.left_out;
  if (!summary.cancelled) {
    trainer.RebuildOccupancy();
    if (!trainer.occupancy().empty()) {
      left_out.push_back(
          {{"what",
            fmt::format("sampling of {:.1f}% of the rays' range (occupancy grid {}^3, {:.1f}% of the "
                        "scene box empty)",
                        100.0 * (1.0 - trainer.occupancy_span_fraction()), config.occupancy_resolution,
                        100.0 * (1.0 - trainer.occupancy().occupied_fraction()))},
           {"why",
            fmt::format("empty: alpha below {} per cell at every probed time", config.occupancy_min_alpha)}});
    }
    eval::ClipEvaluation what;
    what.train_frames = split.train;
    what.heldout_frames = split.heldout;
    metrics = eval::EvaluateClip(clip, uncertainty_renderer, what, out_dir);
    const auto pointer = "/heldout/image/psnr_tissue/mean"_json_pointer;
    if (metrics.contains(pointer) && metrics.at(pointer).is_number())
      summary.heldout_psnr = metrics.at(pointer);
  }
  metrics["iterations"] = trainer.iteration();
  metrics["train_seconds"] = train_seconds;
  // The average over this run's steps (periodic rounds included); the progress line shows the last
  // interval's rate instead.
  metrics["samples_per_second"] = run_samples / std::max(run_step_seconds, 1e-9);
  metrics["cancelled"] = summary.cancelled;
  metrics["curve"] = extras.curve;
  metrics["left_out"] = left_out;
  metrics["field"] = trainer.field().Describe();
  std::vector<eval::CurveSeries> series(2);
  series[0].label = "held-out PSNR (tissue)";
  series[1].label = "training PSNR (batch)";
  series[1].dashed = true;
  for (const auto& point : extras.curve) {
    const double seconds = point["seconds"].get<double>();
    series[0].seconds.push_back(seconds);
    series[0].psnr.push_back(point.contains("heldout_psnr") ? point["heldout_psnr"].get<double>() : NAN);
    series[1].seconds.push_back(seconds);
    series[1].psnr.push_back(point["train_psnr"].get<double>());
  }
  eval::WriteCurveSvg(out_dir / "curve.svg", series);
  summary.metrics_path = (out_dir / "metrics.json").string();
  std::ofstream(summary.metrics_path) << metrics.dump(2);
  eval::WriteReport(out_dir);
  return summary;
}

}  // namespace endorecon
