// endorecon-worker prepare: a clip from a raw stereo recording (two videos or folders, one
// side-by-side or top-bottom video) and its calibration; see worker/prepare/prepare_clip.h.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>

#include "common/prepare_flags_cli.h"
#include "worker/prepare/options_from_flags.h"
#include "worker/runtime/commands.h"
#include "worker/runtime/progress_line.h"

namespace endorecon::worker {

Command AddPrepareCommand(CLI::App& app) {
  auto* cmd =
      app.add_subcommand("prepare", "make a clip from a raw stereo recording (rectify, depth, masks, poses)");
  auto flags = std::make_shared<endorecon::PrepareFlags>();
  auto out = std::make_shared<std::string>();
  cmd->add_option("-o,--out", *out, "clip folder to write (replaces an earlier prepared clip there)")
      ->required();
  AddPrepareFlags(*cmd, *flags);
  return [flags, out] {
    prepare::PrepareOptions options = prepare::OptionsFromFlags(*flags);
    options.out = *out;
    prepare::PrepareHooks hooks;
    hooks.on_frame = [](int done, int total) {
      ShowProgress(total > 0 ? fmt::format(" prepared {}/{} frames ", done, total)
                             : fmt::format(" prepared {} frames ", done));
    };
    const prepare::PrepareSummary summary = prepare::PrepareClip(options, hooks);
    EndProgress();
    spdlog::info(
        "wrote {} ({} layout): {} frames of the recording's {}{}, {:.1f} s ({:.2f} frames/s)",
        summary.clip.string(), summary.layout, summary.frames, summary.recording_frames,
        summary.dropped.empty() ? ""
                                : fmt::format(", {} dropped (could not be placed)", summary.dropped.size()),
        summary.seconds,
        (summary.frames + static_cast<double>(summary.dropped.size())) / std::max(1e-9, summary.seconds));
    // Nothing measured is said as such: "median 0.000 px, RMS 0.000 px" of no match read as a perfect
    // rectification (found 2026-12-07, a mono video given as side by side).
    if (summary.epipolar_error.count > 0) {
      spdlog::info(
          "rectification: epipolar error median {:.3f} px, RMS {:.3f} px ({} matches); depth coverage "
          "{:.1f}%",
          summary.epipolar_error.median, summary.epipolar_error.rms, summary.epipolar_error.count,
          100 * summary.depth_coverage);
    } else {
      spdlog::warn(
          "rectification: no match between the eyes, so no epipolar error measured; depth coverage {:.1f}%",
          100 * summary.depth_coverage);
    }
    if (options.estimate_poses && summary.pose_reprojection.count > 0) {
      spdlog::info("poses: reprojection error median {:.3f} px, RMS {:.3f} px ({} observations)",
                   summary.pose_reprojection.median, summary.pose_reprojection.rms,
                   summary.pose_reprojection.count);
    } else if (options.estimate_poses) {
      spdlog::warn("poses: no reprojection error measured (no frame placed beyond the first)");
    }
    spdlog::info("every choice and per-frame numbers: {}/prepare.json; preview: {}/preview.png",
                 summary.clip.string(), summary.clip.string());
    return 0;
  };
}

}  // namespace endorecon::worker
