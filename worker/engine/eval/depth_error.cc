#include "worker/engine/eval/depth_error.h"

#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>

#include "worker/engine/eval/image_size.h"
#include "worker/engine/eval/summary.h"

namespace endorecon::eval {

DepthError MeasureDepth(std::span<const float> depth, std::span<const float> ground_truth,
                        std::span<const std::uint8_t> tool_mask, int width, int height, double near,
                        double far) {
  CheckImageSize(depth.size(), width, height, 1, "depth error: rendered depth");
  CheckImageSize(ground_truth.size(), width, height, 1, "depth error: ground-truth depth");
  CheckMaskSize(tool_mask.size(), width, height, "depth error: tool mask");
  if (!(far > near)) {
    FailInvalid("depth error: depth range far " + std::to_string(far) + " is not above near " +
                std::to_string(near));
  }
  double squares = 0, absolutes = 0;
  long valid = 0;
  for (std::size_t p = 0; p < depth.size(); ++p) {
    const float gt = ground_truth[p];
    if ((!tool_mask.empty() && tool_mask[p] != 0) || !std::isfinite(gt) || gt <= 0) continue;
    const double diff = static_cast<double>(depth[p]) - gt;
    squares += diff * diff;
    absolutes += std::abs(diff);
    ++valid;
  }
  if (valid == 0) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan, nan, 0};
  }
  const double rmse = std::sqrt(squares / valid);
  return {rmse, absolutes / valid, rmse / (far - near), valid};
}

nlohmann::json ToJson(const DepthError& error) {
  return {{"rmse", error.rmse},
          {"mae", error.mae},
          {"rmse_relative", error.rmse_relative},
          {"valid_pixels", error.valid_pixels}};
}

nlohmann::json ToJson(std::span<const DepthError> frames) {
  nlohmann::json per_frame = nlohmann::json::array();
  for (const DepthError& f : frames) per_frame.push_back(ToJson(f));
  return SummariseFrames(std::move(per_frame), {"rmse", "mae", "rmse_relative"});
}

}  // namespace endorecon::eval
