// The variance of a Gaussian head from its raw log-variance output: sigma^2 = softplus(l) + eps, as
// the paper. Stable for any finite l (no overflow for l up to float max, exact to rounding for
// l down to -80 and beyond, where softplus(l) ~ e^l).
#pragma once

#include "common/hd.h"
#include "worker/engine/field/activations.h"

namespace endorecon::field {

// The default eps (config `variance_eps`), about the variance of 8-bit quantisation
// ((1/255)^2 / 12 = 1.3e-6): the smallest error variance an 8-bit image can show. The floor decides
// what the NLL can learn: where a sample's squared error is below it, the NLL's variance gradient is
// ~1 / (2 var) whatever the error, so every such sample's variance sinks to the floor alike and the
// aleatoric map cannot rank them. With the earlier 1e-3 (an error of 8/255) that was most of the demo
// clip's pixels (median error 1.4/255); measured at 120 s (docs/benchmarks.md): held-out Spearman
// 0.53 -> 0.65, AUSE 0.21 -> 0.13 at eps 1e-3 -> 1e-6, PSNR unchanged within the run-to-run noise.
inline constexpr float kDefaultVarianceEps = 1e-6f;

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
