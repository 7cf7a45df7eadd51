// Monte Carlo dropout moments of one sample over K stochastic passes (paper §3, "To capture epistemic
// uncertainty"): the predictive mean, the aleatoric variance (mean of the predicted variances) and the
// epistemic variance (variance of the K predicted means, population form 1/K). Welford's update, so
// a large density with a small spread keeps its precision in float.
#pragma once

#include "common/hd.h"

namespace endorecon::render {

template <typename S>
struct McMoments {
  S mean = 0;   // running mean of the predicted means
  S m2 = 0;     // running sum of squared deviations of the predicted means
  S noise = 0;  // running sum of the predicted (aleatoric) variances
};

// Adds pass number `pass` (1 for the first) with predicted mean x and predicted variance var.
template <typename S>
ENDORECON_HD void AddPass(McMoments<S>& m, int pass, S x, S var) {
  const S d = x - m.mean;
  m.mean += d / S(pass);
  m.m2 += d * (x - m.mean);
  m.noise += var;
}

// After K passes: E_k[var_k] and Var_k[x_k] (1/K; 0 for K = 1).
template <typename S>
ENDORECON_HD S Aleatoric(const McMoments<S>& m, int passes) {
  return m.noise / S(passes);
}
template <typename S>
ENDORECON_HD S Epistemic(const McMoments<S>& m, int passes) {
  return m.m2 / S(passes);
}

}  // namespace endorecon::render
