// From a raw stereo recording to a clip: `endorecon-worker prepare`, and the preparation phase of
// a job submitted as a recording. Reads the recording once (plus a few frames first, to survey
// the disparities), rectifies, matches, masks and places every selected frame, and writes the
// clip (clip_writer.h) with prepare.json and preview.png into a temporary folder beside `out`
// that is renamed to `out` only when everything is written. See docs/formats.md ("Prepared clips").
#pragma once

#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include "common/prepare_flags.h"
#include "worker/prepare/stereo_depth.h"
#include "worker/prepare/stereo_source.h"
#include "worker/prepare/stereo_survey.h"

namespace endorecon::prepare {

struct PrepareOptions {
  RecordingInput recording;
  std::vector<std::filesystem::path> calibration;  // one OpenCV file or two ROS YAMLs; none with `rectified`
  bool rectified = false;                          // the recording is rectified already
  double focal = 0, baseline = 0;                  // with `rectified`: pixels, clip units
  std::filesystem::path masks;                     // the left eye's tool masks (video or folder); empty: none
  bool masks_tool_black = false;                   // the masks mark the tool 0 (black) instead of 255 (white)
  std::vector<PixelRect> exclude;                  // fixed screen regions, in the recording's stored frames
  FrameRange frames;
  FrameSize size;               // 0x0: the calibration's resolution
  std::filesystem::path poses;  // the left eye's camera-to-world per frame (pose_file.h); empty: fixed
  bool estimate_poses = false;  // estimate a moving endoscope's poses from the frames
  DepthOptions depth;
  std::filesystem::path out;
};

struct PrepareHooks {
  std::function<void(int done, int total)> on_frame;  // after each batch; total -1 while unknown
  std::function<bool()> should_stop;                  // polled between batches
};

struct PrepareSummary {
  std::filesystem::path clip;
  std::string layout;  // "endonerf" or "transforms"
  int frames = 0;      // in the clip
  std::vector<int> dropped;  // the recording's frames selected but not placed (--estimate-poses)
  int recording_frames = 0;
  double seconds = 0;
  ErrorStats epipolar_error;     // of the surveyed matches, pixels
  ErrorStats pose_reprojection;  // --estimate-poses, pixels
  double depth_coverage = 0;     // mean share of non-excluded pixels with a depth
};

// Throws Error: kNotFound for a missing input, kInvalidArgument naming the file and frame for bad
// input (sizes, lengths, calibration, masks, poses, options), kUnavailable when the output cannot
// be written, kCancelled when should_stop said so. Nothing is left in `out` unless it succeeded;
// an earlier prepared clip in `out` (one with prepare.json) is replaced, any other non-empty `out`
// refused before any work.
PrepareSummary PrepareClip(const PrepareOptions& options, const PrepareHooks& hooks = {});

}  // namespace endorecon::prepare
