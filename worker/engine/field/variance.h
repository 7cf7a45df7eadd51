// The variance of a Gaussian head from its raw log-variance output: sigma^2 = softplus(l) + eps, as
// the paper. Stable for any finite l (no overflow for l up to float max, exact to rounding for
// l down to -80 and beyond, where softplus(l) ~ e^l).
#pragma once

#include "common/hd.h"
#include "worker/engine/field/hash_math.h"

namespace endorecon::field {

template <typename S>
ENDORECON_HD S VarianceFromLogVar(S l, S eps) {
  return Softplus(l) + eps;
}

// d VarianceFromLogVar / d l = sigmoid(l).
template <typename S>
ENDORECON_HD S VarianceFromLogVarGrad(S l) {
  return Sigmoid(l);
}

}  // namespace endorecon::field
