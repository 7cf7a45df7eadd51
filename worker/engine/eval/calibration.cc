#include "worker/engine/eval/calibration.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <nlohmann/json.hpp>
#include <numeric>
#include <string>

#include "common/error.h"

namespace endorecon::eval {
namespace {

double Pearson(const std::vector<double>& a, const std::vector<double>& b) {
  const double n = static_cast<double>(a.size());
  const double mean_a = std::accumulate(a.begin(), a.end(), 0.0) / n;
  const double mean_b = std::accumulate(b.begin(), b.end(), 0.0) / n;
  double cov = 0, var_a = 0, var_b = 0;
  for (std::size_t i = 0; i < a.size(); ++i) {
    cov += (a[i] - mean_a) * (b[i] - mean_b);
    var_a += (a[i] - mean_a) * (a[i] - mean_a);
    var_b += (b[i] - mean_b) * (b[i] - mean_b);
  }
  if (var_a == 0 || var_b == 0) return 0;
  return std::clamp(cov / std::sqrt(var_a * var_b), -1.0, 1.0);
}

// Indices of `values` in descending order. Sorted once a vector and shared by its ranks and its
// sparsification curve (a 640 x 512 frame's calibration: 0.13 s sorting each twice, 0.10 s once).
std::vector<std::size_t> OrderDescending(const std::vector<double>& values) {
  std::vector<std::size_t> order(values.size());
  std::iota(order.begin(), order.end(), 0);
  std::sort(order.begin(), order.end(), [&](std::size_t i, std::size_t j) { return values[i] > values[j]; });
  return order;
}

// 1-based ranks (largest value = rank n here; the direction does not change a correlation),
// tied values sharing the average of their ranks; `order` is OrderDescending(values).
std::vector<double> AverageRanks(const std::vector<double>& values, const std::vector<std::size_t>& order) {
  std::vector<double> ranks(values.size());
  for (std::size_t start = 0; start < order.size();) {
    std::size_t end = start + 1;
    while (end < order.size() && values[order[end]] == values[order[start]]) ++end;
    const double rank = (start + 1 + end) / 2.0;  // mean of start+1 .. end
    for (std::size_t i = start; i < end; ++i) ranks[order[i]] = rank;
    start = end;
  }
  return ranks;
}

// Normalised mean error left after removing the first k = floor(f n) pixels in the order of
// `key` (descending; `order` is OrderDescending(key)), for f = i / steps. Ties in `key` are removed
// in expectation: a partly removed tie group takes away its mean error per pixel.
std::vector<double> SparsificationCurve(const std::vector<double>& key, const std::vector<std::size_t>& order,
                                        const std::vector<double>& error, int steps) {
  const std::size_t n = error.size();
  std::vector<double> prefix(n + 1, 0.0);  // prefix[j] = sum of error over order[0 .. j)
  for (std::size_t j = 0; j < n; ++j) prefix[j + 1] = prefix[j] + error[order[j]];
  const double total = prefix[n];
  std::vector<double> curve(steps, 0.0);
  if (total == 0) return curve;
  const double base = total / n;
  std::size_t group_start = 0, group_end = 0;
  for (int i = 0; i < steps; ++i) {
    const std::size_t k = static_cast<std::size_t>(i) * n / steps;
    while (group_end <= k) {  // advance to the tie group holding position k
      group_start = group_end;
      ++group_end;
      while (group_end < n && key[order[group_end]] == key[order[group_start]]) ++group_end;
    }
    const double group_mean = (prefix[group_end] - prefix[group_start]) / (group_end - group_start);
    const double removed = prefix[group_start] + (k - group_start) * group_mean;
    curve[i] = std::max(0.0, total - removed) / (n - k) / base;
  }
  return curve;
}

double TrapezoidArea(const std::vector<double>& x, const std::vector<double>& y) {
  double area = 0;
  for (std::size_t i = 1; i < x.size(); ++i) area += (x[i] - x[i - 1]) * (y[i] + y[i - 1]) / 2;
  return area;
}

}  // namespace

Calibration MeasureCalibration(std::span<const float> uncertainty, std::span<const float> error,
                               std::span<const std::uint8_t> tool_mask, int steps, double resolution) {
  if (uncertainty.size() != error.size() || (!tool_mask.empty() && tool_mask.size() != error.size())) {
    FailInvalid("calibration: uncertainty has " + std::to_string(uncertainty.size()) + " values, error " +
                std::to_string(error.size()) + ", tool mask " + std::to_string(tool_mask.size()) +
                " (expected equal, or an empty mask)");
  }
  if (steps < 1) FailInvalid("calibration: sparsification steps " + std::to_string(steps) + " < 1");

  std::vector<double> u, e;
  u.reserve(error.size());
  e.reserve(error.size());
  bool finite = true;
  for (std::size_t p = 0; p < error.size(); ++p) {
    if (!tool_mask.empty() && tool_mask[p] != 0) continue;
    u.push_back(uncertainty[p]);
    e.push_back(error[p]);
    finite = finite && std::isfinite(uncertainty[p]) && std::isfinite(error[p]);
  }
  Calibration c;
  c.pixels = static_cast<long>(e.size());
  if (e.empty() || !finite || std::accumulate(e.begin(), e.end(), 0.0) < resolution * e.size()) {
    c.pearson = c.spearman = c.ause = std::numeric_limits<double>::quiet_NaN();
    return c;
  }
  c.pearson = Pearson(u, e);
  const std::vector<std::size_t> by_u = OrderDescending(u), by_e = OrderDescending(e);
  c.spearman = Pearson(AverageRanks(u, by_u), AverageRanks(e, by_e));
  for (int i = 0; i < steps; ++i) c.curves.fractions.push_back(static_cast<double>(i) / steps);
  c.curves.by_uncertainty = SparsificationCurve(u, by_u, e, steps);
  c.curves.oracle = SparsificationCurve(e, by_e, e, steps);
  std::vector<double> gap(steps);
  for (int i = 0; i < steps; ++i) gap[i] = c.curves.by_uncertainty[i] - c.curves.oracle[i];
  c.ause = TrapezoidArea(c.curves.fractions, gap);
  return c;
}

CalibrationSummary SummariseCalibration(std::span<const Calibration> frames) {
  std::vector<double> pearson, spearman, ause;
  CalibrationSummary s;
  int with_curves = 0;
  for (const Calibration& f : frames) {
    pearson.push_back(f.pearson);
    spearman.push_back(f.spearman);
    ause.push_back(f.ause);
    if (f.curves.fractions.empty()) continue;
    if (with_curves == 0) {
      s.mean_curves = f.curves;
    } else if (f.curves.fractions.size() != s.mean_curves.fractions.size()) {
      FailInvalid("calibration summary: frames have " + std::to_string(s.mean_curves.fractions.size()) +
                  " and " + std::to_string(f.curves.fractions.size()) + " sparsification steps");
    } else {
      for (std::size_t i = 0; i < f.curves.fractions.size(); ++i) {
        s.mean_curves.by_uncertainty[i] += f.curves.by_uncertainty[i];
        s.mean_curves.oracle[i] += f.curves.oracle[i];
      }
    }
    ++with_curves;
  }
  for (std::size_t i = 0; i < s.mean_curves.fractions.size(); ++i) {
    s.mean_curves.by_uncertainty[i] /= with_curves;
    s.mean_curves.oracle[i] /= with_curves;
  }
  s.pearson = Summarise(pearson);
  s.spearman = Summarise(spearman);
  s.ause = Summarise(ause);
  return s;
}

namespace {

nlohmann::json CurvesJson(const SparsificationCurves& curves) {
  return {
      {"fractions", curves.fractions}, {"by_uncertainty", curves.by_uncertainty}, {"oracle", curves.oracle}};
}

}  // namespace

nlohmann::json ToJson(const Calibration& frame) {
  return {{"pearson", frame.pearson},
          {"spearman", frame.spearman},
          {"ause", frame.ause},
          {"pixels", frame.pixels},
          {"curves", CurvesJson(frame.curves)}};
}

nlohmann::json ToJson(std::span<const Calibration> frames) {
  const CalibrationSummary s = SummariseCalibration(frames);
  nlohmann::json per_frame = nlohmann::json::array();
  for (const Calibration& f : frames) {
    nlohmann::json j = ToJson(f);
    j.erase("curves");
    per_frame.push_back(std::move(j));
  }
  return {{"error_measure", "per-pixel RMSE over RGB, tissue pixels"},
          {"curves_normalised_by", "mean error of all tissue pixels (fraction 0)"},
          {"pearson", ToJson(s.pearson)},
          {"spearman", ToJson(s.spearman)},
          {"ause", ToJson(s.ause)},
          {"curves", CurvesJson(s.mean_curves)},
          {"per_frame", std::move(per_frame)}};
}

}  // namespace endorecon::eval
