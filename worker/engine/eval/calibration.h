// How well a per-pixel uncertainty map predicts where the per-pixel error is: rank and linear
// correlation, and the area under the sparsification error (AUSE, Ilg et al. 2018).
// The error measure is the per-pixel RMSE over the RGB channels (PixelRmse).
#pragma once

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <span>
#include <vector>

#include "worker/engine/eval/summary.h"

namespace endorecon::eval {

// Default number of sparsification steps: fractions 0, 0.02, ..., 0.98.
inline constexpr int kSparsificationSteps = 50;

// Sparsification: remove the fraction f of pixels ranked highest (by uncertainty, or by true error
// for the oracle) and take the mean error of the rest, divided by the mean error of all pixels
// (so both curves start at 1 and are comparable across frames). Where uncertainties tie, the
// expected value under a random order inside the tie is used, so a constant uncertainty gives the
// flat "random" curve at 1. When every error is 0 both curves are 0.
struct SparsificationCurves {
  std::vector<double> fractions;       // i / steps, i = 0 .. steps - 1
  std::vector<double> by_uncertainty;  // normalised mean error left after removing by uncertainty
  std::vector<double> oracle;          // the same, removing by true error: the best possible curve
};

struct Calibration {
  double pearson = 0;   // linear correlation of uncertainty and error
  double spearman = 0;  // Pearson correlation of their ranks, ties given their average rank
  double ause = 0;      // trapezoid area of (by_uncertainty - oracle) over the fractions; 0 is perfect
  long pixels = 0;      // tissue pixels the numbers rest on
  SparsificationCurves curves;
};

// Calibration of `uncertainty` against `error` (one value per pixel each, same length) over tissue
// pixels (`tool_mask` empty, or 0 there; 1 = tool), with `steps` sparsification fractions.
// A correlation with a constant side (zero variance) is defined as 0. With no tissue pixel, a
// non-finite value on one, or a mean error below `resolution` (errors smaller than the measure can
// tell), the three numbers are NaN and the curves empty (never a silent number).
// Throws InvalidArgument when the lengths disagree or steps < 1.
Calibration MeasureCalibration(std::span<const float> uncertainty, std::span<const float> error,
                               std::span<const std::uint8_t> tool_mask, int steps = kSparsificationSteps,
                               double resolution = 0);

// The resolution of a per-pixel error between a rendering and an 8-bit image (in [0, 1] units): half
// a step. A frame rendered within it on average is as exact as its image can tell, and its errors
// rank only float noise (an all-white clip rendered perfectly reported an AUSE of 0.46; found
// 2026-12-06).
inline constexpr double kEightBitErrorResolution = 0.5 / 255;

struct CalibrationSummary {
  Summary pearson, spearman, ause;   // mean ± std over frames
  SparsificationCurves mean_curves;  // per-fraction mean over the frames that have curves
};

// Summary over frames; all frames must use the same number of steps (InvalidArgument otherwise).
CalibrationSummary SummariseCalibration(std::span<const Calibration> frames);

// {"pearson", "spearman", "ause", "pixels", "curves": {"fractions", "by_uncertainty", "oracle"}}.
nlohmann::json ToJson(const Calibration& frame);

// {"error_measure", "pearson": Summary, "spearman": Summary, "ause": Summary, "curves": mean curves,
//  "per_frame": [{"pearson", "spearman", "ause", "pixels"}]} (per-frame curves left out for size).
nlohmann::json ToJson(std::span<const Calibration> frames);

}  // namespace endorecon::eval
