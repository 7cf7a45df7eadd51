#include "worker/engine/reconstruct.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <limits>
#include <thread>

#include "common/error.h"
#include "common/file_write.h"
#include "common/output_folder.h"
#include "worker/engine/base/machine_memory.h"
#include "worker/engine/base/seconds_since.h"
#include "worker/engine/eval/clip_evaluator.h"
#include "worker/engine/eval/eval_plan.h"
#include "worker/engine/eval/one_colour.h"
#include "worker/engine/eval/report.h"
#include "worker/engine/eval/run_outputs.h"
#include "worker/engine/eval/warnings.h"
#include "worker/engine/field/field_description.h"
#include "worker/engine/run_config.h"
#include "worker/engine/scene/clip_loader.h"
#include "worker/engine/scene/outside_view.h"
#include "worker/engine/train/checkpoint.h"
#include "worker/engine/train/render_settings.h"
#include "worker/engine/train/scene_fit.h"
#include "worker/engine/train/trainer.h"
#include "worker/engine/training_loop.h"

namespace endorecon {
namespace {

namespace fs = std::filesystem;
using nlohmann::literals::operator""_json_pointer;

using Clock = std::chrono::steady_clock;

// Records the one-colour yardstick beside the training frames' PSNR (metrics.json:
// train.image.psnr_one_colour) and warns when the reconstruction is no better (eval/one_colour.h).
void CheckItFits(const scene::Clip& clip, const std::vector<int>& train_frames, nlohmann::json& metrics) {
  const auto mean = "/train/image/psnr/mean"_json_pointer;
  if (!metrics.contains(mean) || !metrics[mean].is_number()) return;
  const double yardstick = eval::MeanOneColourPsnr(clip, train_frames);
  if (!std::isfinite(yardstick)) return;
  metrics["train"]["image"]["psnr_one_colour"] = yardstick;
  const double trained = metrics[mean].get<double>();
  if (trained < yardstick + eval::kLeastGainOverOneColourDb) {
    // Said with the iterations: short runs (tens of steps) meet it too, and the config was blamed
    // alone (found 2026-12-07). Whole frames both, as the yardstick is of whole frames (the outcome
    // line's training PSNR is the last batch's).
    const int iterations = metrics.value("iterations", 0);
    eval::Warn(
        metrics,
        fmt::format("the training frames' PSNR over whole frames ({:.2f} dB) is no better than each "
                    "frame's mean colour alone gives ({:.2f} dB): the reconstruction learnt nothing of "
                    "the scene after {} iteration{} (too few for the clip, a learning rate too high, or a "
                    "config that stops the field learning: config.json)",
                    trained, yardstick, iterations, iterations == 1 ? "" : "s"));
  }
}

using base::SecondsSince;

// Evaluation's share of a run by default: the budget is the job's, and training is its main work.
// When even the leanest plan (held-out frames full, the rest reduced) costs more, training gives
// way up to half the run so the budget holds; past that the held-out frames are reduced too once
// rendering them full would overrun by more than the tolerance below, and the run overruns only when
// even the frames all reduced cannot keep to it.
constexpr double kEvaluationShare = 0.25;
constexpr double kEvaluationShareMax = 0.5;

// How far past its budget a run may end (docs/operations.md: "within 10%"): held-out frames are
// reduced only when rendering them full would overrun by more.
constexpr double kBudgetTolerance = 0.1;

// Seconds writing takes after the last frame renders (the uncertainty heat maps, video, model,
// metrics and report page), per pixel of the clip: measured on the 2-core VM (docs/benchmarks.md,
// "The budget is the job") and rounded up.
constexpr double kTailSecondsPerPixel = 1.0e-6;

// What a run keeps per pixel of its clip beside the decoded frames (the sampler's and the uncertainty
// map's tables, evaluation's buffers), and with depth priors the depth refiner's refined priors
// more: 4.1 and 3.7 bytes measured on clips of 33 million pixels with and without depth, masks and
// ground truth (docs/benchmarks.md, "A clip too large for memory"), rounded up.
constexpr double kRunBytesPerPixel = 5;
constexpr double kRunBytesPerDepthPixel = 5;

double TailSeconds(const scene::Clip& clip) {
  return kTailSecondsPerPixel * double(clip.frame_count()) * clip.width * clip.height;
}

// Records what the occupancy grid leaves out of the final field's renders (rebuilt from it).
void RebuildOccupancy(train::Trainer& trainer, nlohmann::json& left_out) {
  trainer.RebuildOccupancy();
  // A grid that leaves nothing out is no entry ("sampling of 0.0% of the rays' range"; found 2026-12-06).
  if (trainer.occupancy().empty() || trainer.occupancy_span_fraction() > 0.9995) return;
  const auto& config = trainer.config();
  left_out.push_back(
      {{"what", fmt::format("sampling of {:.1f}% of the rays' range (occupancy grid {}^3, {:.1f}% of the "
                            "scene box empty)",
                            100.0 * (1.0 - trainer.occupancy_span_fraction()), config.occupancy_resolution,
                            100.0 * (1.0 - trainer.occupancy().occupied_fraction()))},
       {"why", fmt::format("empty: alpha below {} per cell at every probed time", config.occupancy_min_alpha)}});
}

ReconstructSummary RunPipeline(const ReconstructOptions& options, const ReconstructHooks& hooks) {
  const auto run_start = Clock::now();
  const int threads = tbb::this_task_arena::max_concurrency();
  train::TrainConfig config = ResolveConfig(options);
  scene::LoadOptions load;
  load.force_static = options.force_static;
  if (!options.frames_cut) load.frames = options.frames;
  load.should_stop = hooks.should_stop;
  load.fit_depth_bounds = config.fit_depth_bounds;
  load.memory_bytes = options.memory_bytes > 0 ? options.memory_bytes : base::AvailableMemoryBytes();
  load.run_bytes_per_pixel = kRunBytesPerPixel;
  load.run_bytes_per_depth_pixel = kRunBytesPerDepthPixel;
  if (config.background == "black") load.alpha_background = {0, 0, 0};
  nlohmann::json outside_view;  // what the scope's view leaves out, for left_out
  const scene::Clip clip = [&] {
    scene::Clip loaded = [&] {
      try {
        return scene::LoadClip(options.clip_dir, load);
      } catch (const Error& e) {
        if (!options.frames_cut) throw;
        // "poses_bounds.npy row 2" of a clip cut to frames 6:10 is the user's row 8.
        Fail(e.code(), std::string(e.what()) + " (in the clip cut to frames " + options.frames.ToString() +
                           " of the user's: its rows and frames count the picked frames from 0)");
      }
    }();
    if (config.outside_view != "auto") return loaded;
    const std::vector<std::uint8_t> outside = scene::OutsideViewMask(loaded, config.outside_view_level);
    if (outside.empty()) return loaded;
    scene::ExcludeFromFrames(loaded, outside);
    const double share = double(std::count(outside.begin(), outside.end(), 1)) / double(outside.size());
    outside_view = {
        {"what", fmt::format("the {:.1f}% of each frame outside the scope's view", 100 * share)},
        {"why", fmt::format("dark (brightest channel at most {} of 255) in every frame and reaching "
                            "the frame's edge: not tissue, left out of training and evaluation",
                            config.outside_view_level)}};
    spdlog::info("{}: {}", outside_view["what"].get<std::string>(), outside_view["why"].get<std::string>());
    return loaded;
  }();
  const FrameSplit split = SplitFrames(clip.frame_count(), config.holdout);
  // A resumed run keeps its checkpoint's uncertainty-map stride: the map's cells come back from the
  // checkpoint, laid out by the stride its run fitted (or, before 2026-12-04, by none), and a refit
  // with other settings (a resume may change them) would lay them out otherwise.
  const int checkpoint_stride = config.adaptive_map_stride;
  const train::SceneFit fit = train::FitToScene(clip, config, split.train);
  if (!options.resume_from.empty()) config.adaptive_map_stride = checkpoint_stride;
  const fs::path out_dir = options.out_dir;

  const DeviceBackends backends = BackendsFor(options.device);
  train::Trainer trainer(clip, config, split.train, options.seed, backends.step, backends.render);
  train::CheckpointExtras extras;
  if (!options.resume_from.empty()) {
    extras = train::ReadCheckpointState(options.resume_from, trainer, options.frames);
    // The budget is the job's: a job handed back and resumed keeps what it had left.
    spdlog::info("resumed from {} at iteration {} after {:.1f} s of training{}", options.resume_from,
                 trainer.iteration(), extras.train_seconds,
                 options.time_budget_s > 0 ? ", which the time budget counts" : "");
  }
  // Written once the checkpoint is taken, not before: a refused resume left a folder holding only
  // config.json, which later runs and renders took for a reconstruction's results (found 2026-12-07).
  WriteFile(out_dir / "config.json", RunConfigJson(config, options, threads).dump(2), "run configuration");
  extras.frames = options.frames;  // what its checkpoints record
  // A resumed run's deformation is the checkpoint's: nothing to fit. A stop asked for while the clip
  // loaded skips the fit (seconds of optical flow on a large clip: a cancel took 8 s to land); the
  // training loop then stops at its first poll, and metrics.json says the start was not fitted.
  if (!(hooks.should_stop && hooks.should_stop())) trainer.StartDeformation();
  spdlog::info("clip {}: {} frame{}{} {}x{}, {} train / {} held out, {} threads, steps on {}; {}",
               clip.source, clip.frame_count(), clip.frame_count() == 1 ? "" : "s",
               options.frames.SelectsAll() ? "" : " (--frames " + options.frames.ToString() + ")", clip.width,
               clip.height, split.train.size(), split.heldout.size(), threads, trainer.device(),
               field::DescribeField(trainer.field()));
  // Said, as a right eye and its baseline were taken without a word and had no effect (found
  // 2026-12-07): prepare makes depth from both eyes; the reconstruction trains on the left's.
  if (clip.has_stereo()) {
    spdlog::info(
        "the clip's right eye (images_right/) is not trained on: the reconstruction uses the left eye and "
        "its depth maps (endorecon-worker prepare makes those from both eyes)");
  }
  // The renderers run where the steps do and skip what the trainer's occupancy grid says is empty.
  render::FrameRenderer renderer(trainer.field(), trainer.box(),
                                 train::EvalRenderSettings(config, clip.near, clip.far), backends.render);
  render::FrameRenderer uncertainty_renderer(
      trainer.field(), trainer.box(),
      train::UncertaintyRenderSettings(config, clip.near, clip.far, options.seed), backends.render);
  renderer.SetOccupancy(&trainer.occupancy());
  uncertainty_renderer.SetOccupancy(&trainer.occupancy());

  // Reduced frames' colour and depth (eval/eval_plan.h): half the coarse samples per ray.
  render::FrameRenderer reduced_renderer(trainer.field(), trainer.box(),
                                         train::ReducedRenderSettings(config, clip.near, clip.far),
                                         backends.render);
  reduced_renderer.SetOccupancy(&trainer.occupancy());
  const auto MeasureCost = [&] {
    const int f = split.heldout.empty() ? 0 : split.heldout.front();
    return eval::MeasureRenderCost(uncertainty_renderer, reduced_renderer, clip.cameras[f], clip.times[f]);
  };
  const int pixels = scene::RenderedPixels(clip);  // what a frame's render covers: its price
  // --full-eval's price: every frame full (it took 44 s of a 20 s budget when only a quarter was kept for
  // it).
  const auto FullEvaluationSeconds = [&](const eval::RenderCost& cost) {
    return clip.frame_count() * eval::FrameSeconds(eval::FrameRender::kFull, 2, cost, pixels);
  };
  const double tail_s = TailSeconds(clip);
  const bool full_evaluation = options.full_evaluation;
  const double load_s = SecondsSince(run_start);
  const TrainingRun run{
      trainer, clip, split, fit, renderer, uncertainty_renderer, options.time_budget_s, run_start,
      // Evaluation's reserve: its plan within its share, or the leanest plan (with
      // --full-eval every frame full) up to kEvaluationShareMax of the run.
      [&] {
        const double share = kEvaluationShare * options.time_budget_s;
        const double plan = full_evaluation ? FullEvaluationSeconds(MeasureCost())
                                            : eval::PlanEvaluation(clip.frame_count(), split.heldout, pixels,
                                                                   MeasureCost(), share)
                                                  .seconds;
        return std::min(plan, kEvaluationShareMax * options.time_budget_s) + tail_s;
      },
      out_dir / "model" / "checkpoint.bin"};
  const TrainingResult trained = Train(run, hooks, extras);
  const auto after_training = Clock::now();
  trainer.SyncField();
  train::WriteModel(out_dir / "model" / "model.bin", config, trainer.box(), clip.near, clip.far,
                    trainer.field());

  nlohmann::json left_out = fit.left_out;
  if (!outside_view.is_null()) left_out.push_back(outside_view);
  nlohmann::json metrics = nlohmann::json::object();
  double evaluation_s = 0;
  // The leanest plan's price (held-out frames full; with --full-eval every frame), when planned.
  double least_s = -1;
  double advised_s = 0;
  // A stop during evaluation (a cancel, a shutdown) ends the run as one during training does.
  bool cancelled = trained.cancelled;
  if (!cancelled) {
    const auto start = Clock::now();
    RebuildOccupancy(trainer, left_out);
    eval::ClipEvaluation what;
    what.train_frames = split.train;
    what.heldout_frames = split.heldout;
    what.plain = &reduced_renderer;
    if (full_evaluation && options.time_budget_s > 0) {
      // Every frame full, whatever the budget has left: say so when that makes the run late.
      const double available = options.time_budget_s - SecondsSince(run_start) - tail_s;
      least_s = FullEvaluationSeconds(MeasureCost());
      if (least_s > available + kBudgetTolerance * options.time_budget_s) {
        spdlog::warn(
            "--full-eval renders every one of the {} frames with all dropout passes, about {:.0f} s here, "
            "and "
            "the budget leaves {:.0f} s: the run will end more than {:.0f}% late",
            clip.frame_count(), least_s, std::max(available, 0.0), 100 * kBudgetTolerance);
      }
    }
    if (!full_evaluation) {
      // The time evaluation may take: what the budget has left (less the writing after it), or
      // without a budget a third of the training phase (a quarter of the run).
      // From now: the occupancy rebuild above is spent (and without a budget counts in the share).
      const auto now = Clock::now();
      const double available =
          options.time_budget_s > 0
              ? options.time_budget_s - extras.train_seconds + trained.step_seconds -
                    SecondsSince(run_start) - tail_s
              : trained.wall_seconds * kEvaluationShare / (1 - kEvaluationShare) - SecondsSince(start);
      // Held-out frames stay full where the overrun stays within the budget's tolerance; past it
      // the deadline comes first and they are reduced too (a budget too small for the clip's frames).
      const double left = std::max(available, 1e-3);
      const eval::RenderCost cost = MeasureCost();
      least_s = eval::LeastEvaluationSeconds(clip.frame_count(), split.heldout, pixels, cost);
      // How far past `left` held-out frames may still run full: the budget's tolerance, or without a
      // budget without limit (nothing is late; `left` only keeps the training frames to their share).
      const double slack = options.time_budget_s > 0 ? kBudgetTolerance * options.time_budget_s
                                                     : std::numeric_limits<double>::infinity();
      what.plan = eval::PlanEvaluation(clip.frame_count(), split.heldout, pixels, cost, left);
      if (what.plan.seconds > left + slack) {
        what.plan = eval::PlanEvaluation(clip.frame_count(), split.heldout, pixels, cost, left,
                                         eval::HeldOut::kMayReduce);
      }
      what.heldout_slack_s = slack;
      const auto reduced = std::count_if(split.heldout.begin(), split.heldout.end(), [&](int f) {
        return what.plan.at(f) == eval::FrameRender::kReduced;
      });
      if (reduced > 0) {
        spdlog::warn(
            "the time budget cannot afford every held-out frame {}: {} of {} are planned reduced (full again "
            "if the frames run ahead; metrics.json: evaluation.heldout_reduced)",
            config.mc_passes > 0 ? "with all dropout passes" : "at full quality", reduced,
            split.heldout.size());
      }
      if (options.time_budget_s > 0 && what.plan.seconds > left + slack) {
        spdlog::warn(
            "rendering the results of {} frames of {}x{} needs about {:.0f} s at the least, as priced now, "
            "and the budget leaves {:.0f} s: the run will end more than {:.0f}% late unless the frames "
            "render faster than priced (the budget is too small for the clip)",
            clip.frame_count(), clip.width, clip.height, what.plan.seconds, left, 100 * kBudgetTolerance);
      }
      what.deadline = now + std::chrono::duration_cast<Clock::duration>(
                                std::chrono::duration<double>(std::max(available, 0.0)));
    }
    if (hooks.on_progress) {
      // The job's progress goes on through evaluation: frames done of all, and the time left at
      // the pace so far.
      what.on_frame = [&, last = trained.progress](int done, int total) mutable {
        last.phase = "evaluate";
        last.iteration = done;
        last.total_iterations = total;
        last.seconds = SecondsSince(start);
        last.eta_s = last.seconds / std::max(done, 1) * (total - done);
        hooks.on_progress(last);
      };
    }
    what.should_stop = hooks.should_stop;
    try {
      metrics = eval::EvaluateClip(clip, uncertainty_renderer, what, out_dir);
      if (least_s >= 0) {
        // Priced again at the pace the frames rendered: the prices come from a few tenths of a second
        // of rendering, and a busy machine then priced them 2.3x high, advising a budget twice too
        // large (found 2026-12-07).
        nlohmann::json& seconds = metrics["evaluation"]["seconds"];
        const double priced = seconds.value("render_priced", 0.0);
        if (priced > 0) least_s *= seconds.at("render").get<double>() / priced;
        seconds["render_least"] = least_s;
      }
    } catch (const Error& e) {
      if (e.code() != ErrorCode::kCancelled || !what.should_stop || !what.should_stop()) throw;
      spdlog::info("{}", e.what());
      cancelled = true;
      metrics = nlohmann::json::object();
    }
    evaluation_s = SecondsSince(start);
  }
  metrics["iterations"] = trainer.iteration();
  metrics["train_seconds"] = extras.train_seconds;
  metrics["samples_per_second"] = trained.samples_per_second;
  metrics["threads"] = threads;
  metrics["device"] = trainer.device();
  metrics["cancelled"] = cancelled;
  metrics["curve"] = extras.curve;
  metrics["left_out"] = left_out;
  metrics["kept"] = fit.kept;
  metrics["field"] = field::DescribeField(trainer.field());
  // A resumed run reports the start of the run that began it (the checkpoint carries it).
  metrics["deformation_start"] = train::DeformationStartOf(trainer, extras);
  CheckItFits(clip, split.train, metrics);
  eval::WriteCurve(out_dir / "curve.svg", extras.curve);
  // Where this process's time went, up to this file; the report page, written last from it (and
  // showing it as it is), takes a few tenths of a second more, logged.
  metrics["time"] = {{"budget_s", options.time_budget_s},
                     {"total_s", SecondsSince(run_start)},
                     {"load_s", load_s},
                     {"training_s", trained.wall_seconds},
                     {"training_steps_s", trained.step_seconds},
                     {"evaluation_s", evaluation_s},
                     {"writing_s", SecondsSince(after_training) - evaluation_s}};
  // A clip whose results cost more than evaluation's share of the budget took training time: say
  // which budget would have left training its three quarters.
  if (!cancelled && options.time_budget_s > 0 && least_s >= 0 &&
      least_s + tail_s > kEvaluationShare * options.time_budget_s) {
    advised_s = eval::BudgetForEvaluationShare(least_s, tail_s, kEvaluationShare);
    metrics["time"]["budget_advised_s"] = advised_s;
    spdlog::warn(
        "rendering the results of {} frames of {}x{} takes about {:.0f} s at the least here, more than a "
        "quarter of the {:.0f} s budget, so training had {:.0f} s of it; a budget of {:.0f} s or more "
        "would leave training three quarters of the run (metrics.json: time.budget_advised_s)",
        clip.frame_count(), clip.width, clip.height, least_s, options.time_budget_s, trained.wall_seconds,
        advised_s);
  }
  eval::WriteMetrics(out_dir / "metrics.json", metrics);
  eval::WriteReport(out_dir, &clip);
  spdlog::info("run took {:.1f} s ({:.1f} s training, {:.1f} s evaluation{})", SecondsSince(run_start),
               trained.wall_seconds, evaluation_s,
               options.time_budget_s > 0 ? fmt::format(", budget {:.0f} s", options.time_budget_s) : "");

  ReconstructSummary summary;
  summary.cancelled = cancelled;
  summary.iterations = trainer.iteration();
  summary.train_seconds = extras.train_seconds;
  summary.train_psnr = trained.last.psnr;
  summary.threads = threads;
  summary.device = trainer.device();
  summary.metrics_path = (out_dir / "metrics.json").string();
  summary.budget_advised_s = advised_s;
  summary.time_budget_s = options.time_budget_s;
  summary.run_seconds = metrics["time"]["total_s"].get<double>();
  summary.warnings = metrics.value("warnings", std::vector<std::string>{});
  const auto heldout = "/heldout/image/psnr_tissue/mean"_json_pointer;
  if (metrics.contains(heldout) && metrics.at(heldout).is_number())
    summary.heldout_psnr = metrics.at(heldout);
  return summary;
}

}  // namespace

ReconstructSummary Reconstruct(const ReconstructOptions& options, const ReconstructHooks& hooks) {
  CheckOutputFolder(options.out_dir, options.clip_dir, "the clip's folder", ResultsKind::kReconstruction);
  ClearEarlierResults(options.out_dir, ResultsKind::kReconstruction, {options.clip_dir, options.resume_from});
  const int threads = options.threads > 0 ? options.threads : int(std::thread::hardware_concurrency());
  // The run's own arena: two runs in one process (two devices of a worker) each keep their thread count,
  // where tbb::global_control would set one limit for the whole process.
  tbb::task_arena arena(std::max(1, threads));
  return arena.execute([&] { return RunPipeline(options, hooks); });
}

}  // namespace endorecon
