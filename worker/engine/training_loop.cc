#include "worker/engine/training_loop.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "worker/engine/base/seconds_since.h"
#include "worker/engine/eval/curve_probe.h"
#include "worker/engine/train/run_clock.h"

namespace endorecon {
namespace {

using Clock = std::chrono::steady_clock;

using base::SecondsSince;

// The training budget of a run whose time is spent before its first step: one step's worth or less.
constexpr double kLeastBudgetS = 1e-9;

class TrainingLoop {
 public:
  TrainingLoop(const TrainingRun& run, const ReconstructHooks& hooks, train::CheckpointExtras& extras)
      : run_(run),
        hooks_(hooks),
        extras_(extras),
        config_(run.trainer.config()),
        clock_(config_.iterations, run.time_budget_s, extras.train_seconds),
        probe_(run.clip, run.split.heldout, config_.curve_frames),
        curve_(config_.curve_interval_s,
               extras.curve.empty() ? -1 : clock_.seconds() + config_.curve_interval_s),
        progress_line_(hooks.progress_interval_s, 0),
        previews_(hooks.preview_interval_s, 0),
        checkpoints_(hooks.checkpoint_interval_s, 0),
        spent_before_(extras.train_seconds) {
    progress_.total_iterations = config_.iterations;
    progress_.first_iteration = run.trainer.iteration();
  }

  TrainingResult Run() {
    TrainingResult result;
    // A resumed run's last word before its first step is its checkpoint's: a run resumed at its end
    // showed loss 0 and PSNR 0 dB (found 2026-12-07).
    if (!extras_.curve.empty()) {
      const auto& point = extras_.curve.back();
      result.last.loss = point.value("loss", 0.0);
      result.last.psnr = point.value("train_psnr", 0.0);
      progress_.heldout_psnr = point.value("heldout_psnr", -1.0);
      progress_.depth_rmse = point.value("heldout_depth_rmse_relative", -1.0);
    }
    wall_ = Clock::now();
    PriceAfterTraining();
    UpdateBudget();
    while (!clock_.Finished(run_.trainer.iteration())) {
      if (hooks_.should_stop && hooks_.should_stop()) {
        result.cancelled = true;
        break;
      }
      const auto start = Clock::now();
      result.last = run_.trainer.Step(clock_.Progress(run_.trainer.iteration()));
      clock_.AddStep(SecondsSince(start), result.last.samples);
      if (curve_.Due(clock_.seconds()) || run_.trainer.iteration() == config_.iterations) {
        const auto point_start = Clock::now();
        run_.trainer.SyncField();  // the probe and the pricing render the field as it is now
        AddCurvePoint(result.last);
        PriceAfterTraining();
        curve_.Taken(clock_.seconds(), SecondsSince(point_start));
      }
      if (progress_line_.Due(SecondsSince(wall_))) {
        UpdateBudget();
        ReportProgress(result.last, clock_.TakeWindowRate());
      }
      if (hooks_.on_preview && previews_.Due(SecondsSince(wall_))) SendPreviews();
      if (checkpoints_.Due(SecondsSince(wall_))) Checkpoint();
    }
    if (extras_.curve.empty() ||
        extras_.curve.back().at("iteration").get<int>() != run_.trainer.iteration()) {
      run_.trainer.SyncField();
      AddCurvePoint(result.last);
    }
    // The last word on training: a finished job shows where it ended, not its last interval.
    // Its rate is the run's: the interval since the last report may hold no step at all.
    if (!result.cancelled) ReportProgress(result.last, clock_.SamplesPerSecond());
    Checkpoint();
    result.samples_per_second = clock_.SamplesPerSecond();
    result.step_seconds = clock_.seconds() - spent_before_;
    result.wall_seconds = SecondsSince(wall_);
    result.progress = progress_;
    return result;
  }

 private:
  // With a time budget: the training budget (in step seconds) is what the run has left once the
  // work after training is set aside, scaled by the share of this phase's wall time spent in steps
  // (the rest is periodic work). A budget already spent still trains one step (a budget of 0 would
  // read as none, and the run would train until the next update).
  void UpdateBudget() {
    if (run_.time_budget_s <= 0) return;
    const double elapsed = spent_before_ + SecondsSince(run_.run_start);
    const double wall = SecondsSince(wall_);
    const double steps = clock_.seconds() - spent_before_;
    const double share = wall > 1.0 ? std::clamp(steps / wall, 0.2, 1.0) : 1.0;
    clock_.SetBudget(std::max(
        clock_.seconds() + std::max(0.0, run_.time_budget_s - elapsed - reserve_s_) * share, kLeastBudgetS));
  }

  // Re-prices what comes after training on the host field (synced by the caller).
  void PriceAfterTraining() {
    if (run_.time_budget_s <= 0 || !run_.after_training_s) return;
    reserve_s_ = run_.after_training_s();
  }

  void AddCurvePoint(const train::StepStats& stats) {
    nlohmann::json point = {{"seconds", clock_.seconds()},
                            {"iteration", run_.trainer.iteration()},
                            {"loss", stats.loss},
                            {"train_psnr", stats.psnr}};
    if (!probe_.empty()) {  // on the host field, synced by the caller
      const eval::CurveProbe::Point measured = probe_.Measure(run_.renderer);
      progress_.heldout_psnr = measured.psnr;
      progress_.depth_rmse = measured.depth_rmse;
      point["heldout_psnr"] = measured.psnr;
      if (measured.depth_rmse >= 0) point["heldout_depth_rmse_relative"] = measured.depth_rmse;
    }
    extras_.curve.push_back(point);
  }

  void ReportProgress(const train::StepStats& stats, double samples_per_second) {
    const int iteration = run_.trainer.iteration();
    // With a time budget the run may end before its iteration cap: the total is then the count the
    // current pace reaches within the budget, so iteration / total is the share of the run done
    // (and at the end the iterations run).
    const double done = clock_.Progress(iteration);
    const int projected =
        done > 0 ? std::max(iteration, static_cast<int>(std::lround(iteration / done))) : config_.iterations;
    progress_.total_iterations = config_.iterations > 0 ? std::min(config_.iterations, projected) : projected;
    progress_.iteration = iteration;
    progress_.seconds = clock_.seconds();
    progress_.loss = stats.loss;
    progress_.train_psnr = stats.psnr;
    progress_.samples_per_second = samples_per_second;
    progress_.eta_s = clock_.Eta(run_.trainer.iteration());
    if (hooks_.on_progress) hooks_.on_progress(progress_);
  }

  void SendPreviews() {
    run_.trainer.SyncField();
    const int f = run_.split.heldout.empty() ? 0 : run_.split.heldout.front();
    const auto frame =
        run_.uncertainty_renderer.Render(run_.fit.preview_camera(run_.clip.cameras[f]), run_.clip.times[f]);
    hooks_.on_preview(eval::RgbPreview(frame, f));
    if (!frame.uncertainty.empty()) hooks_.on_preview(eval::UncertaintyPreview(frame, f));
  }

  void Checkpoint() {
    extras_.train_seconds = clock_.seconds();
    train::WriteCheckpoint(run_.checkpoint_path, run_.trainer, extras_);
    if (hooks_.on_checkpoint) hooks_.on_checkpoint(run_.checkpoint_path.string());
  }

  const TrainingRun& run_;
  const ReconstructHooks& hooks_;
  train::CheckpointExtras& extras_;
  const train::TrainConfig& config_;
  train::RunClock clock_;
  const eval::CurveProbe probe_;
  train::CurveTimes curve_;
  train::Every progress_line_, previews_, checkpoints_;
  Progress progress_;
  double spent_before_;  // training seconds of earlier processes (a resumed run)
  Clock::time_point wall_;
  double reserve_s_ = 0;  // seconds kept for after training
};

}  // namespace

TrainingResult Train(const TrainingRun& run, const ReconstructHooks& hooks, train::CheckpointExtras& extras) {
  return TrainingLoop(run, hooks, extras).Run();
}

}  // namespace endorecon
