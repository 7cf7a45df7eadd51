// endorecon-worker reconstruct: trains on a clip on this machine and writes the results folder,
// with a live progress line and a summary at the end.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>

#include "worker/engine/reconstruct.h"
#include "worker/engine/scene/json_file.h"
#include "worker/runtime/commands.h"

namespace endorecon::worker {

namespace {

void AddReconstructOptions(CLI::App& cmd, ReconstructOptions& options, std::string& config_file) {
  cmd.add_option("--config", config_file,
                 "JSON file of training keys overriding the preset (as config.json's \"train\")");
  cmd.add_option("--preset", options.preset, "cpu or paper")
      ->capture_default_str()
      ->check(CLI::IsMember({"cpu", "paper"}));
  cmd.add_option("--iterations", options.iterations, "training iterations (default: the preset's)");
  cmd.add_option("--time-budget", options.time_budget_s, "stop training after this many seconds (0: none)")
      ->check(CLI::NonNegativeNumber);
  cmd.add_option("--holdout", options.holdout,
                 "hold every K-th frame out of training (0: none; default: the preset's)");
  cmd.add_option("--seed", options.seed, "random seed")->capture_default_str();
  cmd.add_flag("--static", options.force_static, "treat the clip as static (no deformation network)");
}

}  // namespace

Command AddReconstructCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("reconstruct", "reconstruct a clip here and write the results folder");
  auto options = std::make_shared<ReconstructOptions>();
  auto config_file = std::make_shared<std::string>();
  cmd->add_option("clip", options->clip_dir, "clip folder (EndoNeRF layout or transforms.json)")->required();
  cmd->add_option("-o,--out", options->out_dir, "results folder")->required();
  AddReconstructOptions(*cmd, *options, *config_file);
  cmd->add_option("--threads", options->threads, "worker threads (0: all cores)")->capture_default_str();
  cmd->add_option("--resume", options->resume_from, "checkpoint file to resume from");
  return [options, config_file] {
    if (!config_file->empty()) options->config = scene::ReadJsonFile(*config_file);
    ReconstructHooks hooks;
    hooks.progress_interval_s = 1.0;
    hooks.on_progress = [](const Progress& p) {
      const double percent = p.total_iterations > 0 ? 100.0 * p.iteration / p.total_iterations : 0.0;
      std::fprintf(stderr,
                   "\r iter %6d/%d %5.1f%%  ETA %5.0fs  loss %.4f  PSNR %5.2f dB  held-out %5.2f dB  %.2f M "
                   "samples/s ",
                   p.iteration, p.total_iterations, percent, p.eta_s, p.loss, p.train_psnr, p.heldout_psnr,
                   p.samples_per_second / 1e6);
    };
    const ReconstructSummary summary = Reconstruct(*options, hooks);
    std::fprintf(stderr, "\n");
    spdlog::info("{} {} iterations in {:.1f} s; training PSNR {:.2f} dB; held-out tissue PSNR {}",
                 summary.cancelled ? "stopped after" : "done:", summary.iterations, summary.train_seconds,
                 summary.train_psnr,
                 summary.heldout_psnr >= 0 ? fmt::format("{:.2f} dB", summary.heldout_psnr) : "n/a");
    spdlog::info("results: {}  (metrics: {})", options->out_dir, summary.metrics_path);
    return 0;
  };
}

}  // namespace endorecon::worker
