// The options of `endorecon-worker prepare` as a user gives them (the same flags on `endorecon
// submit` for a raw recording): the recording, its calibration, masks, frame selection, size,
// poses and depth options, and the text forms of frame ranges, sizes and screen regions. The
// worker's `prepare`, the CLI (which checks them before uploading) and the server parse them here.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace endorecon {

// Frames START, START + STEP, ... below END of a recording (0-based, END exclusive). Text
// "START:END:STEP" with every part optional ("10:", ":200", "::2", "5:50:5"); END -1 = to the end.
struct FrameRange {
  int start = 0;
  int end = -1;
  int step = 1;

  bool Selects(int frame) const {
    return frame >= start && (end < 0 || frame < end) && (frame - start) % step == 0;
  }
  bool SelectsAll() const { return start == 0 && end < 0 && step == 1; }
  // The frames it selects of `total` (0 .. total - 1), in order.
  std::vector<int> Of(int total) const;
  // As Of, and throws Error(kInvalidArgument) when it selects none: "PREFIX--frames RANGE picks none
  // of WHOSE TOTAL frames (...)".
  std::vector<int> PickedOf(int total, const std::string& prefix, const std::string& whose) const;
  std::string ToString() const;
};

// Output frame size "WxH", both positive and even (so halves and centres are whole pixels).
struct FrameSize {
  int width = 0, height = 0;
};

// The largest frame a clip may have, in pixels (4096 x 4096; the engine's loaders refuse more).
inline constexpr double kMostFramePixels = 4096.0 * 4096.0;

// A rectangle of pixels "X,Y,W,H": x, y >= 0, width and height > 0.
struct PixelRect {
  int x = 0, y = 0, width = 0, height = 0;
};

// Each throws Error(kInvalidArgument) quoting the text and the expected form.
FrameRange ParseFrameRange(std::string_view text);
FrameSize ParseFrameSize(std::string_view text);
PixelRect ParsePixelRect(std::string_view text);

struct PrepareFlags {
  std::string left, right;               // --left, --right: a video or a folder of frames per eye
  std::string side_by_side;              // --side-by-side: one video (or folder), left eye in the left half
  std::string top_bottom;                // --top-bottom: left eye on top
  std::vector<std::string> calibration;  // --calibration: an OpenCV stereo file, or two ROS camera_info YAMLs
  bool rectified = false;                // --rectified, with --focal PX and --baseline B
  double focal = 0, baseline = 0;
  std::string masks;                 // --masks: the left eye's tool masks (video or folder)
  std::string mask_tool = "white";   // --mask-tool: white (255 = tool) or black (0 = tool)
  std::vector<std::string> exclude;  // --exclude X,Y,W,H (repeatable)
  std::string frames;                // --frames START:END:STEP
  std::string size;                  // --size WxH
  std::string poses;                 // --poses FILE
  bool estimate_poses = false;       // --estimate-poses
  bool depth_refine = false;         // --depth-refine
  // --depth-paths 3|8 (SGBM's 3-way or 8-path mode); 0: 8 with --estimate-poses (3-way depth
  // places the synthetic endoscope 0.6 degrees off, 8 paths within 0.5), else 3.
  int depth_paths = 0;
  // --skip-left N, --skip-right N: with --left/--right, the first N frames of that eye's recording
  // are dropped (it began N frames before the other's; the preparation says so when the eyes'
  // motion shows it: worker/prepare/eye_sync.h).
  int skip_left = 0, skip_right = 0;

  bool empty() const { return left.empty() && right.empty() && side_by_side.empty() && top_bottom.empty(); }
  // Every path the options name (recording, calibration, masks, poses), in that order.
  std::vector<std::string> Paths() const;
};

// Throws Error(kInvalidArgument) when --skip-left or --skip-right is negative, or given without two
// eyes' recordings (`two_sources`: --left with --right). prepare, submit and calibrate take them.
void CheckEyeSkips(bool two_sources, int skip_left, int skip_right);

// Throws Error(kInvalidArgument) saying which flag is wrong: not exactly one recording form
// (--left with --right, --side-by-side, --top-bottom), not exactly one of --calibration (one or two
// files) and --rectified (with --focal and --baseline > 0), --poses with --estimate-poses, a bad
// --mask-tool or --depth-paths, or a text form ParseFrameRange, ParseFrameSize or
// ParsePixelRect refuses.
void CheckPrepareFlags(const PrepareFlags& flags);

}  // namespace endorecon
