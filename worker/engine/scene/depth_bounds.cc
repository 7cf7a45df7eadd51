#include "worker/engine/scene/depth_bounds.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "worker/engine/scene/clip_checks.h"

namespace endorecon::scene {
namespace {

constexpr std::size_t kLattice = 61;  // every 61st pixel of every frame, at most
// A small clip is read more densely, to about kWantedPriors priors: at every 61st pixel a clip of 4
// frames of 16 x 12 gave 12, too few, and kept bounds that left its surface out of every ray's
// reach: black images and zero depth, without a word (found 2026-12-07).
constexpr std::size_t kWantedPriors = 400;
constexpr std::size_t kLeastPriors = 16;   // fewer say too little
constexpr double kMargin = 0.25;           // the priors' range widened by a quarter of its span each way,
constexpr double kLeastMargin = 0.05;      // and by at least this share of their depth
constexpr double kLooseFactor = 2;         // bounds over twice that range are loose
constexpr double kOutsideShare = 0.25;     // bounds leaving more priors outside cut them off

double Percentile(std::vector<float>& values, double p) {
  const auto k = std::ptrdiff_t(p * double(values.size() - 1));
  std::nth_element(values.begin(), values.begin() + k, values.end());
  return values[std::size_t(k)];
}

}  // namespace

std::string FitBoundsToPriors(Clip& clip) {
  if (!clip.has_depth() || clip.object_radius > 0) return {};
  std::size_t pixels = 0;
  for (const auto& frame : clip.depth) pixels += frame.size();
  const std::size_t lattice = std::clamp<std::size_t>(pixels / kWantedPriors, 1, kLattice);
  std::vector<float> priors;
  std::size_t outside = 0, foreign = 0;
  for (const auto& frame : clip.depth) {
    for (std::size_t i = 0; i < frame.size(); i += lattice) {
      const float z = frame[i];
      if (!(z > 0) || !std::isfinite(z)) continue;
      priors.push_back(z);
      outside += z < clip.near || z > clip.far;
      foreign += InOtherUnits(z, clip.near, clip.far);
    }
  }
  if (priors.size() < kLeastPriors || 2 * foreign > priors.size()) return {};
  // Widened by a quarter of their span each way, and by a twentieth of their depth at least (priors
  // of one value have no span; found 2026-12-06), never below half the lowest: a thin, far surface's
  // priors widened by a quarter of their depth became seven times their span.
  const double p_lo = Percentile(priors, 0.005), p_hi = Percentile(priors, 0.995);
  const double margin = std::max(kMargin * (p_hi - p_lo), kLeastMargin * p_hi);
  const double lo = std::max(0.5 * p_lo, p_lo - margin), hi = p_hi + margin;
  const bool loose = clip.far - clip.near > kLooseFactor * (hi - lo);
  const double cut = double(outside) / double(priors.size());
  if (!loose && cut <= kOutsideShare) return {};
  const std::string why = fmt::format(
      "the depth bounds [{:.6g}, {:.6g}] {} the depth priors (their 0.5th to 99.5th percentile, widened by a "
      "quarter of their span: [{:.6g}, {:.6g}]{}): the bounds are now that range, so the samples and "
      "the grids' cells lie where the surface is",
      clip.near, clip.far, loose ? "are over twice as wide as" : "cut off", lo, hi,
      loose ? "" : fmt::format("; {:.0f}% of the priors lay outside the bounds", 100 * cut));
  clip.near = lo;
  clip.far = hi;
  return why;
}

}  // namespace endorecon::scene
