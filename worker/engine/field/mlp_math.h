// Per-element math of the MLPs' hidden layers (ReLU, then inverted dropout), written once for the CPU
// tile loops and the CUDA layer kernels.
#pragma once

#include <cstdint>

#include "common/hd.h"
#include "worker/engine/field/dropout.h"

namespace endorecon::field {

// How one layer's mask is drawn in one pass: off, or the key, threshold and survivors' scale.
template <typename S>
struct HiddenDropout {
  bool on = false;
  DropoutKey key;
  std::uint32_t threshold = 0;  // round(rate * 2^32)
  S keep_scale = S(1);          // 1 / (1 - rate)
};

// Unit j of row `row` (the row's index in the whole pass) of a hidden layer `width` wide.
template <typename S>
ENDORECON_HD S HiddenActivation(S pre, const HiddenDropout<S>& d, std::uint32_t row, int width, int j) {
  if (!(pre > S(0))) return S(0);
  if (!d.on) return pre;
  const std::uint32_t counter = row * static_cast<std::uint32_t>(width) + static_cast<std::uint32_t>(j);
  return DropoutKeep(d.key, counter, d.threshold) ? pre * d.keep_scale : S(0);
}

// The gradient through it, read back from the kept activation (zero where ReLU or the mask stopped it).
template <typename S>
ENDORECON_HD S HiddenActivationGrad(S activation, S grad, S keep_scale) {
  return activation > S(0) ? grad * keep_scale : S(0);
}

}  // namespace endorecon::field
