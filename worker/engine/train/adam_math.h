// Adam's update of one parameter, written once for the CPU optimiser's loop and the CUDA fused kernel.
#pragma once

#include <cmath>

#include "common/hd.h"

namespace endorecon::train {

// The step of one Adam update, the same for every parameter of a block: lr_t = lr sqrt(c2) / c1 and
// eps_t = eps sqrt(c2) with the bias corrections c1 = 1 - beta1^t, c2 = 1 - beta2^t.
struct AdamCoefficients {
  float beta1 = 0.9f, beta2 = 0.99f;
  float step = 0;   // lr_t
  float eps = 0;    // eps_t
  float scale = 1;  // gradient clipping's factor
};

// m <- beta1 m + (1 - beta1) g, v <- beta2 v + (1 - beta2) g^2, value <- value - lr_t m / (sqrt(v) + eps_t),
// with g = scale * grad.
ENDORECON_HD void AdamUpdate(float& value, float grad, float& m, float& v, const AdamCoefficients& c) {
  const float g = grad * c.scale;
  m = c.beta1 * m + (1 - c.beta1) * g;
  v = c.beta2 * v + (1 - c.beta2) * g * g;
  value -= c.step * m / (std::sqrt(v) + c.eps);
}

}  // namespace endorecon::train
