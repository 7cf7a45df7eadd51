#include "worker/engine/scene/exposure_change.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace endorecon::scene {
namespace {

constexpr std::size_t kLattice = 7;  // every 7th pixel
constexpr int kDark = 8, kBright = 247;
constexpr std::size_t kLeastSamples = 16;  // fewer pixels in a channel say nothing
constexpr double kStandardErrors = 3;      // a shift within this many standard errors is none

double Median(std::vector<double>& values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

bool ShowsTool(const Clip& clip, int frame, std::size_t pixel) {
  return clip.has_masks() && clip.tool_mask[static_cast<std::size_t>(frame)][pixel] != 0;
}

}  // namespace

double ExposureChange(const Clip& clip, const std::vector<int>& frames) {
  std::vector<double> changes;
  std::vector<double> ratios;
  const std::size_t pixels = static_cast<std::size_t>(clip.width) * static_cast<std::size_t>(clip.height);
  for (std::size_t k = 1; k < frames.size(); ++k) {
    const int fa = frames[k - 1], fb = frames[k];
    const auto& a = clip.rgb[static_cast<std::size_t>(fa)];
    const auto& b = clip.rgb[static_cast<std::size_t>(fb)];
    double change = -1;
    for (int c = 0; c < 3; ++c) {
      ratios.clear();
      for (std::size_t p = 0; p < pixels; p += kLattice) {
        if (ShowsTool(clip, fa, p) || ShowsTool(clip, fb, p)) continue;
        const int va = a[3 * p + c], vb = b[3 * p + c];
        if (va < kDark || vb < kDark || va > kBright || vb > kBright) continue;
        ratios.push_back(std::log((vb + 1.0) / (va + 1.0)));
      }
      if (ratios.size() < kLeastSamples) continue;
      const double median = Median(ratios);
      // The median's standard error from the spread (1.4826 MAD: the normal's sigma; 1.2533 sigma /
      // sqrt(n): a median's error), so a few pixels' noise or motion read as no shift: a 10 x 8 clip's
      // 11 samples, or a noisy or fast-moving clip's, turned the gains on (found 2026-12-06).
      for (double& r : ratios) r = std::abs(r - median);
      const double spread = 1.4826 * Median(ratios);
      const double error = 1.2533 * spread / std::sqrt(double(ratios.size()));
      change = std::max(change, std::max(0.0, std::abs(median) - kStandardErrors * error));
    }
    if (change >= 0) changes.push_back(change);
  }
  return changes.empty() ? 0.0 : Median(changes);
}

}  // namespace endorecon::scene
