// The field's scalar activations, shared by the heads, the variance map and the CUDA kernels. Each is
// a pure function written to stay finite for every finite input.
#pragma once

#include <cmath>

#include "common/hd.h"

namespace endorecon::field {

// Density activation: exp(min(x, 15)). The cap keeps a runaway raw value from overflowing float
// (e^15 ~ 3.3e6 is far beyond any useful density). TruncExpGrad is exp(min(x, 15)) too, also above
// the cap (as instant-ngp's trunc_exp): a density stuck above the cap still gets a gradient back down.
template <typename S>
ENDORECON_HD S TruncExp(S x) {
  return std::exp(x < S(15) ? x : S(15));
}

template <typename S>
ENDORECON_HD S TruncExpGrad(S x) {
  return TruncExp(x);
}

// Logistic sigmoid, never overflowing (exp of a non-positive argument only).
template <typename S>
ENDORECON_HD S Sigmoid(S x) {
  if (x >= S(0)) return S(1) / (S(1) + std::exp(-x));
  const S e = std::exp(x);
  return e / (S(1) + e);
}

// log(1 + e^x) without overflow for large x or loss of precision for very negative x.
template <typename S>
ENDORECON_HD S Softplus(S x) {
  return (x > S(0) ? x : S(0)) + std::log1p(std::exp(-std::fabs(x)));
}

}  // namespace endorecon::field
