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

// 1 / the mean of `values` over the tissue; 0 when that mean is not positive.
double TissueMeanScale(std::span<const float> values, std::span<const std::uint8_t> tool_mask) {
  double sum = 0;
  long count = 0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (!tool_mask.empty() && tool_mask[i] != 0) continue;
    sum += values[i];
    ++count;
  }
  return sum > 0 ? double(count) / sum : 0.0;
}

}  // namespace

std::vector<float> RelativeToBrightnessMedian(std::span<const float> rgb, std::span<const float> values,
                                              std::span<const std::uint8_t> tool_mask) {
  const std::size_t n = values.size();
  if (rgb.size() != 3 * n || (!tool_mask.empty() && tool_mask.size() != n)) {
    FailInvalid("RelativeToBrightnessMedian: " + std::to_string(rgb.size()) + " colour values, " +
                std::to_string(n) + " values and " + std::to_string(tool_mask.size()) +
                " mask values do not describe one set of pixels");
  }
  // The curve: the median value per brightness bin over the tissue.
  std::array<std::vector<float>, kNoiseCurveBins> bins;
  for (std::size_t i = 0; i < n; ++i) {
    if (tool_mask.empty() || tool_mask[i] == 0) bins[BinOf(&rgb[3 * i])].push_back(values[i]);
  }
  std::array<double, kNoiseCurveBins> curve{};
  std::array<bool, kNoiseCurveBins> known{};
  for (int b = 0; b < kNoiseCurveBins; ++b) {
    auto& in_bin = bins[b];
    if (in_bin.empty()) continue;
    std::nth_element(in_bin.begin(), in_bin.begin() + in_bin.size() / 2, in_bin.end());
    curve[b] = in_bin[in_bin.size() / 2];
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
  std::vector<float> relative(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double level = curve[BinOf(&rgb[3 * i])];
    relative[i] = level > 0 ? static_cast<float>(values[i] / level) : 0.0f;
  }
  return relative;
}

std::vector<float> ModelUncertainty(std::span<const float> rgb, std::span<const float> aleatoric,
                                    std::span<const float> epistemic,
                                    std::span<const std::uint8_t> tool_mask) {
  const std::size_t n = aleatoric.size();
  if (rgb.size() != 3 * n || epistemic.size() != n || (!tool_mask.empty() && tool_mask.size() != n)) {
    FailInvalid("ModelUncertainty: " + std::to_string(rgb.size()) + " colour values, " + std::to_string(n) +
                " aleatoric, " + std::to_string(epistemic.size()) + " epistemic and " +
                std::to_string(tool_mask.size()) + " mask values do not describe one set of pixels");
  }
  // The aleatoric score over the noise the camera adds at the pixel's brightness, as the model learned it.
  const std::vector<float> excess = RelativeToBrightnessMedian(rgb, aleatoric, tool_mask);
  // Each term relative to its mean over the tissue (a term that is 0 everywhere adds nothing).
  const double excess_scale = TissueMeanScale(excess, tool_mask);
  const double epistemic_scale = TissueMeanScale(epistemic, tool_mask);
  std::vector<float> map(n);
  for (std::size_t i = 0; i < n; ++i)
    map[i] = static_cast<float>(excess[i] * excess_scale + epistemic[i] * epistemic_scale);
  return map;
}

void AddNeighbourTerm(std::span<float> map, std::span<const float> term, double weight,
                      std::span<const std::uint8_t> tool_mask) {
  if (term.size() != map.size() || (!tool_mask.empty() && tool_mask.size() != map.size())) {
    FailInvalid("AddNeighbourTerm: a map of " + std::to_string(map.size()) + " pixels, " +
                std::to_string(term.size()) + " term and " + std::to_string(tool_mask.size()) +
                " mask values");
  }
  const double scale = weight * TissueMeanScale(term, tool_mask);
  for (std::size_t i = 0; i < map.size(); ++i) map[i] += static_cast<float>(term[i] * scale);
}

}  // namespace endorecon::eval
