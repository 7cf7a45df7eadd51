// PSNR (peak 1) from a mean squared error, capped: the one formula the training step's PSNR and
// every evaluated frame's share, so the curve, the log and metrics.json agree on the cap.
#pragma once

#include <algorithm>
#include <cmath>

namespace endorecon::base {

// PSNR of identical images is infinite; metrics report this cap instead (an MSE of 1e-10), so
// every number in metrics.json is finite and averages over frames stay meaningful.
inline constexpr double kPsnrCapDb = 100.0;

// NaN stays NaN (no pixel to measure).
inline double PsnrFromMse(double mse) {
  if (std::isnan(mse)) return mse;
  return std::min(kPsnrCapDb, -10.0 * std::log10(std::max(mse, 0.0)));
}

}  // namespace endorecon::base
