// Central finite differences for gradient checks in float64.
#pragma once

#include <cmath>

namespace endorecon::testing {

// (f(x + h) - f(x - h)) / (2h), with x restored afterwards. f reads x through the reference.
template <typename F>
double CentralDifference(double& x, double h, const F& f) {
  const double saved = x;
  x = saved + h;
  const double plus = f();
  x = saved - h;
  const double minus = f();
  x = saved;
  return (plus - minus) / (2 * h);
}

// |a - b| <= tol * max(1, |a|, |b|): absolute near zero, relative for large values.
inline bool CloseRelative(double a, double b, double tol) {
  const double scale = std::fmax(1.0, std::fmax(std::fabs(a), std::fabs(b)));
  return std::fabs(a - b) <= tol * scale;
}

}  // namespace endorecon::testing
