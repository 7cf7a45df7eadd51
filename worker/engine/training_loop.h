// The training phase of a run: steps until the iteration cap or the time budget runs out or a stop
// is asked for, with the periodic work around them on their own intervals: the progress line, the
// previews, the checkpoints (resumable: the curve and the elapsed time travel in them) and the points
// of the error-against-run-time curve. The schedule is the run clock's (train/run_clock.h). A time
// budget is the whole run's: training gets what is left of it once what comes after training
// (priced at every curve point on the field as it is then) and the periodic work are set aside.
#pragma once

#include <chrono>
#include <filesystem>
#include <functional>

#include "worker/engine/reconstruct.h"
#include "worker/engine/render/frame_renderer.h"
#include "worker/engine/run_config.h"
#include "worker/engine/scene/clip.h"
#include "worker/engine/train/checkpoint.h"
#include "worker/engine/train/scene_fit.h"
#include "worker/engine/train/trainer.h"

namespace endorecon {

// What the training phase works with; everything must outlive the call.
struct TrainingRun {
  train::Trainer& trainer;
  const scene::Clip& clip;
  const FrameSplit& split;
  const train::SceneFit& fit;
  render::FrameRenderer& renderer;              // curve points (no uncertainty)
  render::FrameRenderer& uncertainty_renderer;  // previews
  double time_budget_s = 0;  // the whole run's, seconds; 0: none
  std::chrono::steady_clock::time_point run_start;  // when the run began (loading included)
  // Seconds the run needs after training (evaluation and writing), priced on the field as it is
  // when called (at the start and at every curve point, with a budget).
  std::function<double()> after_training_s;
  std::filesystem::path checkpoint_path;
};

struct TrainingResult {
  bool cancelled = false;
  train::StepStats last;          // of the last step
  double samples_per_second = 0;  // this process's steps on average (periodic rounds included)
  double step_seconds = 0;        // this process's seconds in steps
  double wall_seconds = 0;        // this process's seconds in the phase (periodic work included)
  Progress progress;              // the last progress reported
};

// Runs the phase and writes a last checkpoint; extras (the curve, the training seconds) are updated
// as it goes. Throws what Trainer::Step throws (divergence: nothing more is written).
TrainingResult Train(const TrainingRun& run, const ReconstructHooks& hooks, train::CheckpointExtras& extras);

}  // namespace endorecon
