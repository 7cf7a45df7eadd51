// The engine's one entry point for a whole run: load a clip, train, evaluate, write results.
// Used by `endorecon-worker reconstruct` and, in-process, by the worker runtime (one call per device).
// The pipeline reads as reconstruct.cc; its stages: run_config.h (what the run is configured with and
// trains on), training_loop.h (the training phase and its periodic work), eval/ (results).
#pragma once

#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>

#include "common/prepare_flags.h"
#include "worker/engine/eval/preview.h"

namespace endorecon {

struct ReconstructOptions {
  std::string clip_dir;  // EndoNeRF layout or a folder with transforms.json
  std::string out_dir;   // results folder; created if missing
  // Keys of the training configuration (config.json's "train" object) overriding the preset, or on
  // resume the checkpoint's configuration; unknown keys are an error naming them.
  nlohmann::json config = nlohmann::json::object();
  std::string preset = "cpu";  // "cpu" or "paper"
  int iterations = -1;         // -1: the preset's
  // 0: none; otherwise the whole run's seconds (loading, training, evaluation, writing; within 10%),
  // and the iteration count is a cap only when given.
  double time_budget_s = 0;
  int holdout = -1;            // -1: the preset's; 0: none; K: every K-th frame held out
  int threads = 0;             // 0: all cores; the run's own TBB arena, other runs in the process keep theirs
  std::string device = "cpu";  // where the training steps run: "cpu" or "cuda:N" (run_config.h BackendFor)
  std::uint64_t seed = 0;
  bool force_static = false;  // treat the clip as static (no deformation network)
  // Every frame rendered with all dropout passes at every pixel, whatever it costs; otherwise the
  // evaluation keeps to a quarter of the run (eval/eval_plan.h).
  bool full_evaluation = false;
  // Optional checkpoint file to resume training from; its configuration replaces the preset, and
  // config, iterations and holdout still apply over it (a field of another shape fails to load).
  std::string resume_from;
  // The memory the run may take, in bytes; a clip that needs more is refused before its frames are
  // decoded (scene/load_options.h). 0: what this machine has available when the run starts
  // (base/machine_memory.h AvailableMemoryBytes).
  std::uint64_t memory_bytes = 0;
  // What report.html calls the run (config.json "title"): a service job's name; empty: the clip
  // folder's name (a job's clip folder is "clip": every job's report was "endorecon report: clip").
  std::string title;
  // The clip folder's frames to reconstruct (config.json "frames"; scene/load_options.h): default all.
  FrameRange frames;
  // The clip is cut to `frames` already (a service job's: the CLI uploads the picked frames alone):
  // they are recorded (config.json, checkpoints), not picked again.
  bool frames_cut = false;
};

struct Progress {
  int iteration = 0;
  int first_iteration = 0;  // where this process's training began: a resumed run's checkpoint's iteration
  // The iteration cap, or with a time budget the iterations the current pace reaches within it
  // (iteration / total_iterations is the share of the run done; at the end, the iterations run).
  int total_iterations = 0;
  double seconds = 0;
  double eta_s = 0;
  double loss = 0;
  double train_psnr = 0;
  double heldout_psnr = -1;  // -1 until measured
  double depth_rmse =
      -1;  // held-out depth RMSE / (far - near); -1 without ground-truth depth or not yet measured
  double samples_per_second = 0;
  // "" while training; "evaluate" while the results are rendered: iteration / total_iterations
  // then count frames, seconds and eta_s are the evaluation's, the other fields keep training's last.
  std::string phase;
};

struct ReconstructHooks {
  std::function<void(const Progress&)> on_progress;            // every progress interval
  std::function<void(const eval::Preview&)> on_preview;        // every preview interval
  std::function<void(const std::string& path)> on_checkpoint;  // after each checkpoint is written
  std::function<bool()> should_stop;                           // polled every iteration; true = cancel
  double progress_interval_s = 2.0;
  double preview_interval_s = 30.0;
  double checkpoint_interval_s = 120.0;
};

struct ReconstructSummary {
  bool cancelled = false;
  int iterations = 0;
  double train_seconds = 0;
  double heldout_psnr = -1;
  double train_psnr = 0;
  int threads = 0;           // the run's arena's concurrency
  std::string device;        // where the steps ran
  std::string metrics_path;  // out_dir/metrics.json
  // > 0 when the clip's results cost more than evaluation's quarter of the time budget: the budget
  // that would have left training three quarters (metrics.json time.budget_advised_s).
  double budget_advised_s = 0;
  double time_budget_s = 0;  // the run's --time-budget (0: none)
  double run_seconds = 0;    // the whole run, up to metrics.json (metrics.json time.total_s)
  // What the results' reader must know, also logged: metrics.json's "warnings" (eval/warnings.h).
  std::vector<std::string> warnings;
};

// Throws endorecon::Error: kInvalidArgument for a bad clip or option (message names the file),
// kInternal when training diverges (message names the stage and iteration; nothing is written, so
// out_dir/model/checkpoint.bin stays the last periodic one, to resume from with another config),
// kUnavailable / kResourceExhausted when a result cannot be written (message names the file),
// kCancelled never (a stop request returns with cancelled = true).
ReconstructSummary Reconstruct(const ReconstructOptions& options, const ReconstructHooks& hooks);

}  // namespace endorecon
