#include "worker/engine/reconstruct.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <filesystem>
#include <thread>

#include "common/file_write.h"
#include "worker/engine/eval/clip_evaluator.h"
#include "worker/engine/eval/report.h"
#include "worker/engine/eval/run_outputs.h"
#include "worker/engine/field/field_description.h"
#include "worker/engine/run_config.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/train/checkpoint.h"
#include "worker/engine/train/render_settings.h"
#include "worker/engine/train/scene_fit.h"
#include "worker/engine/train/trainer.h"
#include "worker/engine/training_loop.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;
using nlohmann::literals::operator""_json_pointer;

// Renders and measures every frame into out_dir with the final field (occupancy rebuilt from it), and
// records what the occupancy grid left out.
nlohmann::json Evaluate(train::Trainer& trainer, const scene::Clip& clip, const FrameSplit& split,
                        render::FrameRenderer& renderer, const fs::path& out_dir, nlohmann::json& left_out) {
  trainer.RebuildOccupancy();
  if (!trainer.occupancy().empty()) {
    const auto& config = trainer.config();
    left_out.push_back(
        {{"what", fmt::format("sampling of {:.1f}% of the rays' range (occupancy grid {}^3, {:.1f}% of the "
                              "scene box empty)",
                              100.0 * (1.0 - trainer.occupancy_span_fraction()), config.occupancy_resolution,
                              100.0 * (1.0 - trainer.occupancy().occupied_fraction()))},
         {"why",
          fmt::format("empty: alpha below {} per cell at every probed time", config.occupancy_min_alpha)}});
  }
  eval::ClipEvaluation what;
  what.train_frames = split.train;
  what.heldout_frames = split.heldout;
  return eval::EvaluateClip(clip, renderer, what, out_dir);
}

ReconstructSummary RunPipeline(const ReconstructOptions& options, const ReconstructHooks& hooks) {
  const int threads = tbb::this_task_arena::max_concurrency();
  scene::LoadOptions load;
  load.force_static = options.force_static;
  const scene::Clip clip = scene::LoadClip(options.clip_dir, load);
  train::TrainConfig config = ResolveConfig(options);
  const FrameSplit split = SplitFrames(clip.frame_count(), config.holdout);
  const train::SceneFit fit = train::FitToScene(clip, config);
  const fs::path out_dir = options.out_dir;
  WriteFile(out_dir / "config.json", RunConfigJson(config, options, threads).dump(2), "run configuration");

  train::Trainer trainer(clip, config, split.train, options.seed);
  train::CheckpointExtras extras;
  if (!options.resume_from.empty()) {
    extras = train::ReadCheckpointState(options.resume_from, trainer);
    spdlog::info("resumed from {} at iteration {}", options.resume_from, trainer.iteration());
  }
  spdlog::info("clip {}: {} frames {}x{}, {} train / {} held out, {} threads; {}", clip.source,
               clip.frame_count(), clip.width, clip.height, split.train.size(), split.heldout.size(), threads,
               field::DescribeField(trainer.field()));
  // Both renderers skip what the trainer's occupancy grid says is empty.
  render::FrameRenderer renderer(trainer.field(), trainer.box(),
                                 train::EvalRenderSettings(config, clip.near, clip.far));
  render::FrameRenderer uncertainty_renderer(
      trainer.field(), trainer.box(),
      train::UncertaintyRenderSettings(config, clip.near, clip.far, options.seed));
  renderer.SetOccupancy(&trainer.occupancy());
  uncertainty_renderer.SetOccupancy(&trainer.occupancy());

  const TrainingRun run{trainer,
                        clip,
                        split,
                        fit,
                        renderer,
                        uncertainty_renderer,
                        options.time_budget_s,
                        out_dir / "model" / "checkpoint.bin"};
  const TrainingResult trained = Train(run, hooks, extras);
  train::WriteModel(out_dir / "model" / "model.bin", config, trainer.box(), clip.near, clip.far,
                    trainer.field());

  nlohmann::json left_out = fit.left_out;
  nlohmann::json metrics = trained.cancelled
                               ? nlohmann::json::object()
                               : Evaluate(trainer, clip, split, uncertainty_renderer, out_dir, left_out);
  metrics["iterations"] = trainer.iteration();
  metrics["train_seconds"] = extras.train_seconds;
  metrics["samples_per_second"] = trained.samples_per_second;
  metrics["threads"] = threads;
  metrics["cancelled"] = trained.cancelled;
  metrics["curve"] = extras.curve;
  metrics["left_out"] = left_out;
  metrics["field"] = field::DescribeField(trainer.field());
  eval::WriteCurve(out_dir / "curve.svg", extras.curve);
  eval::WriteMetrics(out_dir / "metrics.json", metrics);
  eval::WriteReport(out_dir);

  ReconstructSummary summary;
  summary.cancelled = trained.cancelled;
  summary.iterations = trainer.iteration();
  summary.train_seconds = extras.train_seconds;
  summary.train_psnr = trained.last.psnr;
  summary.threads = threads;
  summary.metrics_path = (out_dir / "metrics.json").string();
  const auto heldout = "/heldout/image/psnr_tissue/mean"_json_pointer;
  if (metrics.contains(heldout) && metrics.at(heldout).is_number())
    summary.heldout_psnr = metrics.at(heldout);
  return summary;
}

}  // namespace

ReconstructSummary Reconstruct(const ReconstructOptions& options, const ReconstructHooks& hooks) {
  const int threads = options.threads > 0 ? options.threads : int(std::thread::hardware_concurrency());
  // The run's own arena: two runs in one process (two devices of a worker) each keep their thread count,
  // where tbb::global_control would set one limit for the whole process.
  tbb::task_arena arena(std::max(1, threads));
  return arena.execute([&] { return RunPipeline(options, hooks); });
}

}  // namespace endorecon
