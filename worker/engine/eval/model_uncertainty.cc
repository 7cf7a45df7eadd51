#include "worker/engine/eval/model_uncertainty.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>

#include "common/error.h"

namespace endorecon::eval {
namespace {

int BinOf(const float* rgb) {
  const double brightness = (double(rgb[0]) + rgb[1] + rgb[2]) / 3;
  return std::clamp(int(brightness * kNoiseCurveBins), 0, kNoiseCurveBins - 1);
}

}  // namespace

std::vector<float> ModelUncertainty(std::span<const float> rgb, std::span<const float> aleatoric,
                                    std::span<const float> epistemic,
                                    std::span<const std::uint8_t> tool_mask) {
  const std::size_t n = aleatoric.size();
  if (rgb.size() != 3 * n || epistemic.size() != n || (!tool_mask.empty() && tool_mask.size() != n)) {
    FailInvalid("ModelUncertainty: " + std::to_string(rgb.size()) + " colour values, " + std::to_string(n) +
                " aleatoric, " + std::to_string(epistemic.size()) + " epistemic and " +
                std::to_string(tool_mask.size()) + " mask values do not describe one set of pixels");
  }
  const auto tissue = [&](std::size_t i) { return tool_mask.empty() || tool_mask[i] == 0; };
  // The noise curve: the median aleatoric score per brightness bin over the tissue.
  std::array<std::vector<float>, kNoiseCurveBins> bins;
  for (std::size_t i = 0; i < n; ++i) {
    if (tissue(i)) bins[BinOf(&rgb[3 * i])].push_back(aleatoric[i]);
  }
  std::array<double, kNoiseCurveBins> curve{};
  std::array<bool, kNoiseCurveBins> known{};
  for (int b = 0; b < kNoiseCurveBins; ++b) {
    auto& values = bins[b];
    if (values.empty()) continue;
    std::nth_element(values.begin(), values.begin() + values.size() / 2, values.end());
    curve[b] = values[values.size() / 2];
    known[b] = true;
  }
  for (int b = 0; b < kNoiseCurveBins; ++b) {  // empty bins: the nearest known one's
    for (int d = 1; !known[b] && d < kNoiseCurveBins; ++d) {
      if (b - d >= 0 && known[b - d]) {
        curve[b] = curve[b - d];
        break;
      }
      if (b + d < kNoiseCurveBins && known[b + d]) {
        curve[b] = curve[b + d];
        break;
      }
    }
  }
  std::vector<double> excess(n);
  double excess_sum = 0, epistemic_sum = 0;
  long count = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double noise = curve[BinOf(&rgb[3 * i])];
    excess[i] = noise > 0 ? aleatoric[i] / noise : 0.0;
    if (!tissue(i)) continue;
    excess_sum += excess[i];
    epistemic_sum += epistemic[i];
    ++count;
  }
  // Each term relative to its mean over the tissue (a term that is 0 everywhere adds nothing).
  const double excess_scale = excess_sum > 0 ? double(count) / excess_sum : 0.0;
  const double epistemic_scale = epistemic_sum > 0 ? double(count) / epistemic_sum : 0.0;
  std::vector<float> map(n);
  for (std::size_t i = 0; i < n; ++i)
    map[i] = static_cast<float>(excess[i] * excess_scale + epistemic[i] * epistemic_scale);
  return map;
}

}  // namespace endorecon::eval
