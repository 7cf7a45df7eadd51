// Gradient checks of the field's modules: analytic gradients against central differences in float64.
#pragma once

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "tests/unit/central_difference.h"

namespace endorecon::testing {

struct GradientTolerance {
  double h = 1e-6;
  double rel = 1e-6;  // of the larger of the two magnitudes
  double abs = 1e-9;
};

// For each index i: expects analytic[i] == d loss / d x[i] by central differences (x[i] is perturbed
// and restored). Returns how many of the checked gradients are non-zero, so callers can assert the
// check was not vacuous.
template <typename Loss>
int ExpectGradientMatches(double* x, const double* analytic, const std::vector<std::size_t>& indices,
                          const Loss& loss, const std::string& what, const GradientTolerance& tol = {}) {
  int nonzero = 0;
  for (std::size_t i : indices) {
    const double numeric = CentralDifference(x[i], tol.h, loss);
    const double scale = std::fmax(std::fabs(numeric), std::fabs(analytic[i]));
    EXPECT_NEAR(analytic[i], numeric, tol.abs + tol.rel * scale) << what << "[" << i << "]";
    if (std::fabs(numeric) > 1e-9) ++nonzero;
  }
  return nonzero;
}

// `count` distinct indices in [0, size) (all of them when count >= size), reproducibly.
inline std::vector<std::size_t> SomeIndices(std::size_t size, std::size_t count, std::uint64_t seed) {
  std::vector<std::size_t> all(size);
  for (std::size_t i = 0; i < size; ++i) all[i] = i;
  if (count >= size) return all;
  std::mt19937_64 rng(seed);
  std::shuffle(all.begin(), all.end(), rng);
  all.resize(count);
  return all;
}

inline std::vector<double> RandomValues(std::size_t size, double lo, double hi, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(lo, hi);
  std::vector<double> v(size);
  for (auto& x : v) x = u(rng);
  return v;
}

// Sum of w[i] * y[i]: a scalar loss whose gradient with respect to y is w.
inline double Dot(const std::vector<double>& w, const std::vector<double>& y) {
  double s = 0;
  for (std::size_t i = 0; i < w.size(); ++i) s += w[i] * y[i];
  return s;
}

}  // namespace endorecon::testing
