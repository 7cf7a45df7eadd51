// Stereo calibration from a checkerboard recording (`endorecon-worker calibrate`): the board's
// inner corners found in both eyes (OpenCV's sector-based detector), each eye calibrated
// (calibrateCamera; k1, k2, p1, p2, and k3 only when asked), then both together (stereoCalibrate,
// intrinsics refined jointly).
#pragma once

#include <opencv2/core.hpp>
#include <string>

#include "common/prepare_flags.h"
#include "worker/prepare/stereo_calibration.h"
#include "worker/prepare/stereo_source.h"

namespace endorecon::prepare {

struct CheckerboardOptions {
  cv::Size inner_corners{9, 6};  // columns x rows of inner corners
  double square = 1;             // side of a square, in the unit the calibration (and clips) will use
  FrameRange frames;
  int max_views = 40;  // views used, spread evenly over those where both eyes see the board
  // Fit the radial term k3 too (wide-angle lenses). Off by default: with k1 and k2 free, k3 trades
  // off against k2 inside the views' reach and bends the corners the board never reached.
  bool fit_k3 = false;
};

struct CheckerboardCalibration {
  StereoCalibration calibration;
  double rms_px = 0;  // stereoCalibrate's RMS reprojection error over both eyes
  double left_rms_px = 0, right_rms_px = 0;
  int frames_read = 0, views_found = 0, views_used = 0;
};

// Eyes calibrated closer than this many squares apart are one eye given twice (a stereo endoscope's
// eyes lie about a millimetre or more apart, boards' squares a few millimetres).
constexpr double kLeastBaselineSquares = 1e-3;

// A calibration whose RMS reprojection error is over this many pixels is warned of: a sharp board
// calibrates well under 1 px; a --board of other inner corners than the board's (5x4 for 9x6) found
// corners anyway and calibrated to 4.6 px, a baseline 28 times off, without a word (found 2026-12-06).
constexpr double kMostPlausibleRmsPx = 1.0;

// Eyes that each calibrate plausibly alone but as a pair more than this many times worse than the
// worse of them and over kMostPlausibleRmsPx saw the board at different moments: the synthetic rig's
// views with the left eye's recording begun one view early calibrated to 0.10 px and 0.10 px alone,
// 16 px together, a baseline of 100 for 5 (measured 2026-12-07).
constexpr double kMostPairToEyeRmsRatio = 4.0;

// The warning for `result`, or "" when its error is plausible.
std::string CalibrationWarning(const CheckerboardCalibration& result, const CheckerboardOptions& options);

// Throws the source's errors, and FailInvalid naming the recording when fewer than 4 frames show
// the whole board to both eyes, when the eyes calibrate to less than kLeastBaselineSquares apart, or
// when they calibrate well alone but not together (kMostPairToEyeRmsRatio: views of different
// moments). Eyes of two files are checked to be in step (CheckEyesInStep) when the recording is
// long enough to tell.
CheckerboardCalibration CalibrateFromCheckerboard(const RecordingInput& recording,
                                                  const CheckerboardOptions& options);

}  // namespace endorecon::prepare
