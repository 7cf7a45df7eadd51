// endorecon-worker reconstruct: trains on a clip on this machine and writes the results folder,
// with a live progress line and a summary at the end.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <memory>

#include "common/cli_checks.h"
#include "common/clip_files.h"
#include "common/dicom/uid.h"
#include "common/dicom_file.h"
#include "common/dicom_values.h"
#include "common/error.h"
#include "common/job_bounds.h"
#include "common/json_file.h"
#include "common/recording_flags_cli.h"
#include "worker/engine/reconstruct.h"
#include "worker/engine/run_config.h"
#include "worker/runtime/commands.h"
#include "worker/runtime/dicom_job.h"
#include "worker/runtime/progress_line.h"

namespace endorecon::worker {

namespace {

namespace fs = std::filesystem;

// The clip made from a DICOM recording goes to OUT.clip, replacing an earlier run's clip there; any
// other folder by that name (the user's files) is refused, not deleted.
void RefuseToReplaceAForeignFolder(const fs::path& clip_out) {
  std::error_code error;
  if (!fs::exists(clip_out, error)) return;
  if (fs::is_directory(clip_out, error) && (fs::is_empty(clip_out, error) || FindClipLayout(clip_out)))
    return;
  FailInvalid(clip_out.string() +
              ": exists and is not a clip an earlier run made; the clip of this recording goes there (-o OUT "
              "makes OUT.clip): move it away or choose another -o");
}

void AddReconstructOptions(CLI::App& cmd, ReconstructOptions& options, std::string& config_file) {
  cmd.add_option("--config", config_file,
                 "JSON file of training keys overriding the preset (as config.json's \"train\")");
  cmd.add_option("--preset", options.preset, "cpu, gpu or paper")
      ->capture_default_str()
      ->check(CLI::IsMember({"cpu", "gpu", "paper"}));
  cmd.add_option("--iterations", options.iterations,
                 "training iterations (default: the preset's; with --time-budget: no cap unless given)")
      ->check(AboveZero());
  cmd.add_option("--time-budget", options.time_budget_s,
                 "seconds for the whole run: training, evaluation and writing (0: none)")
      ->check(TimeBudget());
  cmd.add_flag("--full-eval", options.full_evaluation,
               "render every frame with all dropout passes at every pixel (default: evaluation keeps to a "
               "quarter of the run)");
  cmd.add_option("--holdout", options.holdout,
                 "hold every K-th frame out of training (0: none, else K >= 2; default: the preset's)")
      ->check(HoldoutSpacing());
  cmd.add_option("--seed", options.seed, "random seed")->capture_default_str()->check(AtLeastZero());
  cmd.add_flag("--static", options.force_static, "treat the clip as static (no deformation network)");
}

void AddDicomOptions(CLI::App& cmd, v1::RecordingOptions& recording, v1::DicomOutputOptions& dicom) {
  AddRecordingFlags(cmd, recording);
  cmd.add_option_function<std::string>(
      "--frames", [&](const std::string& v) { recording.set_frames(v); },
      "the frames to reconstruct, START:END:STEP (as a Python slice) of a DICOM recording or a clip "
      "folder (its frames in its own order)");
  cmd.add_option_function<std::string>(
      "--size", [&](const std::string& v) { recording.set_size(v); },
      "DICOM recording: scale every frame (each eye) to WxH, even, the recording's aspect ratio (e.g. "
      "320x180 for a 1280x720 recording); default: as recorded");
  AddDicomResultFlags(cmd, dicom);
  cmd.add_option_function<std::string>(
      "--uid-root", [&](const std::string& v) { dicom.set_uid_root(v); },
      "root of the DICOM results' new UIDs (default: 2.25 UUID-derived UIDs)");
}

}  // namespace

Command AddReconstructCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("reconstruct", "reconstruct a clip here and write the results folder");
  auto options = std::make_shared<ReconstructOptions>();
  auto config_file = std::make_shared<std::string>();
  auto recording = std::make_shared<v1::RecordingOptions>();
  auto dicom = std::make_shared<v1::DicomOutputOptions>();
  cmd->add_option("clip", options->clip_dir,
                  "clip folder (EndoNeRF layout or transforms.json), or a DICOM recording (file or folder)")
      ->required();
  cmd->add_option("-o,--out", options->out_dir, "results folder")->required();
  AddReconstructOptions(*cmd, *options, *config_file);
  cmd->add_option("--threads", options->threads, "worker threads (0: all cores)")
      ->capture_default_str()
      ->check(AtLeastZero());
  cmd->add_option("--device", options->device, "where the training steps run: cpu or cuda:N")->capture_default_str();
  cmd->add_option("--resume", options->resume_from, "checkpoint file to resume from");
  AddDicomOptions(*cmd, *recording, *dicom);
  return [options, config_file, recording, dicom] {
    if (!config_file->empty()) {
      options->config = ReadJsonFile(*config_file);
      try {  // checked now, naming the file, not after the clip is loaded
        ResolveConfig(*options);
      } catch (const Error& e) {
        if (e.code() != ErrorCode::kInvalidArgument) throw;
        FailInvalid("--config " + *config_file + ": " + e.what());
      }
    }
    const bool recording_input = dicom::HoldsDicom(options->clip_dir);
    dicom::CheckDicomResultFlags(dicom->enabled(), recording_input, dicom->patient_id(),
                                 dicom->patient_name(), dicom->study_uid());
    // The results' UIDs before the run, not after it (they failed the command once everything else
    // was written; found 2026-12-05). NewUid refuses a root that is no UID prefix.
    if (!dicom->study_uid().empty()) dicom::CheckUid(dicom->study_uid(), "--study-uid");
    if (!dicom->uid_root().empty()) dicom::NewUid(dicom->uid_root());
    if (recording_input) RefuseToReplaceAForeignFolder(options->out_dir + ".clip");
    const auto from_dicom = PrepareRecording(options->clip_dir, *recording, options->out_dir + ".clip");
    if (from_dicom) {
      // The page names the recording, not the clip made of it beside the results (OUT.clip).
      options->title = PathName(options->clip_dir);
      options->clip_dir = from_dicom->clip_dir.string();
    }
    options->frames = ClipFolderFrames(from_dicom, *recording);
    ReconstructHooks hooks;
    hooks.progress_interval_s = 1.0;
    hooks.on_progress = [](const Progress& p) {
      if (p.phase == "evaluate") {
        ShowProgress(fmt::format(" evaluating the results: frame {}/{}  ETA {:4.0f}s{:60}", p.iteration,
                                 p.total_iterations, p.eta_s, ""));
        return;
      }
      const double percent = p.total_iterations > 0 ? 100.0 * p.iteration / p.total_iterations : 0.0;
      // No held-out frames (or none scored yet): -1, not shown as a PSNR.
      const std::string heldout =
          p.heldout_psnr >= 0 ? fmt::format("  held-out {:5.2f} dB", p.heldout_psnr) : "";
      ShowProgress(fmt::format(
          " iter {:6}/{} {:5.1f}%  ETA {:5.0f}s  loss {:.4f}  PSNR {:5.2f} dB{}  {:.2f} M samples/s ",
          p.iteration, p.total_iterations, percent, std::min(p.eta_s, 1e9), p.loss, p.train_psnr, heldout,
          p.samples_per_second / 1e6));
    };
    const ReconstructSummary summary = Reconstruct(*options, hooks);
    EndProgress();
    // No training PSNR when this process ran no step (a resume whose budget was spent), as the CLI.
    spdlog::info(
        "{} {} iteration{} in {:.1f} s; training PSNR {}; {}",
        summary.cancelled ? "stopped after" : "done:", summary.iterations, summary.iterations == 1 ? "" : "s",
        summary.train_seconds, summary.train_psnr > 0 ? fmt::format("{:.2f} dB", summary.train_psnr) : "n/a",
        summary.heldout_psnr >= 0 ? fmt::format("held-out tissue PSNR {:.2f} dB", summary.heldout_psnr)
                                  : "no frame held out");
    if (!summary.cancelled) WriteJobDicom(options->out_dir, from_dicom, *dicom);
    spdlog::info("results: {}  (metrics: {})", options->out_dir, summary.metrics_path);
    return 0;
  };
}

}  // namespace endorecon::worker
