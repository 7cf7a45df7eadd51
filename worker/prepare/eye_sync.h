// Whether two eyes' recordings start together. Two files, one per eye, are paired frame by frame
// in their order, and each file's times count from its own first frame, so two recordings cut at
// different moments pair frames of different moments without any time telling. What each eye sees
// move does: how much each horizontal band of its picture changes from one frame to the next is one
// signal in a rig's two cameras (their disparity moves things along the rows, not across the bands),
// and the lag at which the two eyes' signals match best is how many frames one recording began
// before the other.
#pragma once

#include <opencv2/core.hpp>

#include "worker/prepare/stereo_source.h"

namespace endorecon::prepare {

// How the eyes' motion matches: the right eye's signal `frames` later than the left's matches it
// best (> 0: the left eye's recording began that many frames before the right's).
struct EyeLag {
  int frames = 0;
  double match = 0;            // the signals' correlation at that lag (-1..1)
  double match_in_step = 0;    // at lag 0, the frames as given
  double match_elsewhere = 0;  // the best other peak, more than 2 frames from `frames`
  int samples = 0;             // frames compared
  // The lags about `frames` that match within 0.03 of it (a scene that moves smoothly matches
  // nearly as well a frame or two off): the lag is known to lie among them.
  int earliest = 0, latest = 0;
  // The lag is clear: enough samples, a strong match there, a clearly weaker one as given (or, at a
  // sharp and strong peak, a weaker one) and at every other lag but its neighbours (a rhythm matches
  // a period away as well).
  bool OutOfStep() const;
};

// How much a picture changed since the previous one, band by band: a kBands x 1 column (CV_32F) of
// the mean absolute difference of their grey levels in each of kBands horizontal bands, at most 64
// pixels wide. `previous` is updated to `frame`'s small grey copy; the first frame (empty
// `previous`) gives zeros.
cv::Mat FrameChange(const cv::Mat& frame, cv::Mat& previous);
constexpr int kBands = 8;

// The lag in [-max_lag, max_lag] at which `right` matches `left` best: two signals of one row per
// band and one column per frame (CV_32F), correlated (Pearson) over the middle of `right` slid over
// `left`, as their departures from their own running average.
EyeLag MatchLag(const cv::Mat& left, const cv::Mat& right, int max_lag);

// What a recording too short for the check is told: `prepare` warns that a lag would pass unseen;
// `calibrate` is quiet, its stereo fit telling views of different moments apart itself
// (checkerboard_calibration.h), as a board's usual 20-40 views are too few for the motion.
enum class TooShortToCheck { kWarn, kQuiet };

// Reads up to kSyncFrames pairs of a two-file recording from its start (after its skips) and
// throws FailInvalid naming both files when the eyes' motion says they are out of step, with the
// --skip-left or --skip-right that pairs them. A recording of one file (side by side, top-bottom)
// is one moment per frame and is not read.
void CheckEyesInStep(const RecordingInput& input, TooShortToCheck too_short = TooShortToCheck::kWarn);

constexpr int kSyncFrames = 500;  // 20 s at 25 fps; the lag searched: up to a quarter of those read

}  // namespace endorecon::prepare
