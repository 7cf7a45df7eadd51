// Rendered depth against ground-truth depth.
#pragma once

#include <cstdint>
#include <nlohmann/json_fwd.hpp>
#include <span>

namespace endorecon::eval {

struct DepthError {
  double rmse = 0;           // clip units
  double mae = 0;            // clip units
  double rmse_relative = 0;  // rmse / (far - near): the fraction of the clip's depth range
  long valid_pixels = 0;     // pixels the numbers rest on
};

// Errors of `depth` (float z-depth, width*height, clip units) against `ground_truth` over valid
// pixels: tissue (`tool_mask` empty or 0 there) with a finite ground truth > 0 (0 = unknown).
// A non-finite rendered depth on a valid pixel makes the result NaN (it is an error, not a gap).
// All three numbers are NaN when no pixel is valid. Throws InvalidArgument on bad sizes or when
// far <= near.
DepthError MeasureDepth(std::span<const float> depth, std::span<const float> ground_truth,
                        std::span<const std::uint8_t> tool_mask, int width, int height, double near,
                        double far);

// {"rmse", "mae", "rmse_relative", "valid_pixels"}.
nlohmann::json ToJson(const DepthError& error);

// Per-frame list and a Summary of each number over the frames: {"rmse": {mean, std, ...}, ...,
// "per_frame": [...]}.
nlohmann::json ToJson(std::span<const DepthError> frames);

}  // namespace endorecon::eval
