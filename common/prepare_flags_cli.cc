#include "common/prepare_flags_cli.h"

#include <CLI/CLI.hpp>

#include "common/cli_checks.h"

namespace endorecon {

void AddPrepareFlags(CLI::App& cmd, PrepareFlags& f) {
  const std::string recording = "Recording (one form)", calibration = "Calibration (one form)",
                    extras = "Masks, frames, poses", depth = "Depth";
  cmd.add_option("--left", f.left, "the left eye: a video file or a folder of frames")->group(recording);
  cmd.add_option("--right", f.right, "the right eye: a video file or a folder of frames")->group(recording);
  cmd.add_option("--side-by-side", f.side_by_side,
                 "one video (or folder) of both eyes, left eye in the left half")
      ->group(recording);
  cmd.add_option("--top-bottom", f.top_bottom, "one video (or folder) of both eyes, left eye on top")
      ->group(recording);
  cmd.add_option("--skip-left", f.skip_left,
                 "with --left/--right: drop the left eye's first N frames (its recording began N frames "
                 "before the right's; the preparation says N when the eyes' motion shows it)")
      ->check(AtLeastZero())
      ->group(recording);
  cmd.add_option("--skip-right", f.skip_right, "with --left/--right: drop the right eye's first N frames")
      ->check(AtLeastZero())
      ->group(recording);
  cmd.add_option("--calibration", f.calibration,
                 "OpenCV stereo calibration (K1 D1 K2 D2 R T; YAML or XML), or two ROS camera_info YAMLs "
                 "(left right)")
      ->expected(1, 2)
      ->group(calibration);
  cmd.add_flag("--rectified", f.rectified, "the recording is rectified already (give --focal and --baseline)")
      ->group(calibration);
  cmd.add_option("--focal", f.focal, "with --rectified: focal length in pixels")->group(calibration);
  cmd.add_option("--baseline", f.baseline, "with --rectified: distance between the eyes (the clip's unit)")
      ->group(calibration);
  cmd.add_option("--masks", f.masks, "the left eye's tool masks: a video or a folder, one per frame")
      ->group(extras);
  cmd.add_option("--mask-tool", f.mask_tool, "which mask value marks the tool: white (255) or black (0)")
      ->capture_default_str()
      ->group(extras);
  cmd.add_option(
         "--exclude", f.exclude,
         "X,Y,W,H: a fixed screen region (overlay, toolbar) excluded from training and metrics; repeatable")
      ->group(extras);
  cmd.add_option("--frames", f.frames,
                 "START:END:STEP: the recording's frames to use (0-based, END exclusive; with submit, a "
                 "DICOM recording's or a clip folder's too, in its own order)")
      ->group(extras);
  cmd.add_option("--size", f.size,
                 "WxH: the clip's frame size (default: the calibration's resolution; with submit, a DICOM "
                 "recording's frames are scaled to it, even and of the recording's aspect ratio, default as "
                 "recorded)")
      ->group(extras);
  cmd.add_option("--poses", f.poses,
                 "per-frame camera-to-world of the left eye (JSON or CSV, docs/formats.md)")
      ->group(extras);
  cmd.add_flag("--estimate-poses", f.estimate_poses,
               "estimate a moving endoscope's poses from the stereo frames")
      ->group(extras);
  cmd.add_flag("--depth-refine", f.depth_refine,
               "Lucas-Kanade sub-pixel refinement of every disparity (slower)")
      ->group(depth);
  cmd.add_option("--depth-paths", f.depth_paths,
                 "SGBM directions: 3 (fast; the default) or 8 (3x slower; the default with --estimate-poses)")
      ->group(depth);
}

}  // namespace endorecon
