// endorecon-worker calibrate: an OpenCV stereo calibration file from a checkerboard recording of
// both eyes; reports the RMS reprojection error. See worker/prepare/checkerboard_calibration.h.
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <filesystem>
#include <memory>

#include "common/cli_checks.h"
#include "common/error.h"
#include "common/prepare_flags.h"
#include "worker/prepare/checkerboard_calibration.h"
#include "worker/runtime/commands.h"

namespace endorecon::worker {
namespace {

struct CalibrateFlags {
  std::string out, left, right, side_by_side, top_bottom, board = "9x6", frames;
  double square = 0;
  int max_views = 40;
  int skip_left = 0, skip_right = 0;
  bool fit_k3 = false;
};

prepare::RecordingInput Recording(const CalibrateFlags& f) {
  const int forms = (!f.left.empty() || !f.right.empty()) + !f.side_by_side.empty() + !f.top_bottom.empty();
  if (forms != 1 || f.left.empty() != f.right.empty()) {
    FailInvalid("give the checkerboard recording as --left with --right, or --side-by-side, or --top-bottom");
  }
  CheckEyeSkips(!f.left.empty(), f.skip_left, f.skip_right);
  if (!f.side_by_side.empty()) return {prepare::StereoLayout::kSideBySide, {}, {}, f.side_by_side};
  if (!f.top_bottom.empty()) return {prepare::StereoLayout::kTopBottom, {}, {}, f.top_bottom};
  return {prepare::StereoLayout::kTwoSources, f.left, f.right, {}, f.skip_left, f.skip_right};
}

cv::Size Board(const std::string& text) {
  const auto x = text.find('x');
  try {
    const int columns = std::stoi(text.substr(0, x)), rows = std::stoi(text.substr(x + 1));
    if (x != std::string::npos && columns >= 2 && rows >= 2) return {columns, rows};
  } catch (const std::exception&) {
  }
  FailInvalid("--board '" + text + "': expected COLUMNSxROWS of inner corners (e.g. 9x6)");
}

}  // namespace

Command AddCalibrateCommand(CLI::App& app) {
  auto* cmd = app.add_subcommand("calibrate", "make a stereo calibration file from a checkerboard recording");
  auto f = std::make_shared<CalibrateFlags>();
  cmd->add_option("-o,--out", f->out, "calibration file to write (.yaml or .xml)")->required();
  cmd->add_option("--left", f->left, "the left eye: a video file or a folder of frames");
  cmd->add_option("--right", f->right, "the right eye: a video file or a folder of frames");
  cmd->add_option("--side-by-side", f->side_by_side, "one video of both eyes, left eye in the left half");
  cmd->add_option("--top-bottom", f->top_bottom, "one video of both eyes, left eye on top");
  cmd->add_option("--skip-left", f->skip_left,
                  "with --left/--right: drop the left eye's first N frames (its recording began N frames "
                  "before the right's; said when the eyes' motion shows it)")
      ->check(AtLeastZero());
  cmd->add_option("--skip-right", f->skip_right, "with --left/--right: drop the right eye's first N frames")
      ->check(AtLeastZero());
  cmd->add_option("--board", f->board, "inner corners of the checkerboard, COLUMNSxROWS")
      ->capture_default_str();
  cmd->add_option("--square", f->square, "side of a square, in the unit the clip will use (e.g. mm)")
      ->required()
      ->check(AboveZero());
  cmd->add_option("--frames", f->frames, "START:END:STEP: the frames to search for the board");
  cmd->add_option("--max-views", f->max_views, "views used at most, spread over those found")
      ->capture_default_str()
      ->check(AboveZero());
  return [f] {
    // Before the boards are searched for (seconds), not after: -o names a file.
    if (std::filesystem::is_directory(f->out))
      FailInvalid("-o " + f->out + ": a folder; -o names the calibration file to write (.yaml or .xml)");
    prepare::CheckerboardOptions options;
    options.inner_corners = Board(f->board);
    options.square = f->square;
    options.max_views = f->max_views;
    options.fit_k3 = f->fit_k3;
    if (!f->frames.empty()) options.frames = ParseFrameRange(f->frames);
    const auto result = prepare::CalibrateFromCheckerboard(Recording(*f), options);
    prepare::WriteStereoCalibration(f->out, result.calibration,
                                    {{"rms_reprojection_error_px", result.rms_px},
                                     {"left_rms_reprojection_error_px", result.left_rms_px},
                                     {"right_rms_reprojection_error_px", result.right_rms_px},
                                     {"views", result.views_used}});
    spdlog::info("board found in both eyes in {} of {} frames; {} views used", result.views_found,
                 result.frames_read, result.views_used);
    spdlog::info(
        "RMS reprojection error {:.3f} px (left eye alone {:.3f} px, right eye alone {:.3f} px); baseline "
        "{:.4g}",
        result.rms_px, result.left_rms_px, result.right_rms_px, result.calibration.baseline());
    if (const std::string warning = prepare::CalibrationWarning(result, options); !warning.empty())
      spdlog::warn("{}", warning);
    spdlog::info("wrote {}", f->out);
    return 0;
  };
}

}  // namespace endorecon::worker
