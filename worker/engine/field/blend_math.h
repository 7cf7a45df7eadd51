// Per-sample math of the temporal blend (temporal_blend.h, grid_ensemble.h), written once for the CPU
// modules and the CUDA kernels: the softmax of the blend's logits, the blend of G grids' features with
// those weights, and the gradients of both.
#pragma once

#include <cmath>

#include "common/hd.h"

namespace endorecon::field {

// b[0..g): logits in, weights out (max-shifted, so no overflow).
template <typename S>
ENDORECON_HD void SoftmaxInPlace(S* b, int g) {
  S top = b[0];
  for (int i = 1; i < g; ++i) top = b[i] > top ? b[i] : top;
  S sum = S(0);
  for (int i = 0; i < g; ++i) sum += (b[i] = std::exp(b[i] - top));
  for (int i = 0; i < g; ++i) b[i] /= sum;
}

// dlogit_i = beta_i (dbeta_i - sum_k beta_k dbeta_k).
template <typename S>
ENDORECON_HD void SoftmaxBackward(const S* beta, const S* dbeta, int g, S* dlogits) {
  S mean = S(0);
  for (int i = 0; i < g; ++i) mean += beta[i] * dbeta[i];
  for (int i = 0; i < g; ++i) dlogits[i] = beta[i] * (dbeta[i] - mean);
}

// f[0..d) = sum_i beta_i feats[i * d ..].
template <typename S>
ENDORECON_HD void BlendFeatures(const S* beta, const S* feats, int g, int d, S* f) {
  for (int j = 0; j < d; ++j) f[j] = beta[0] * feats[j];
  for (int i = 1; i < g; ++i) {
    for (int j = 0; j < d; ++j) f[j] += beta[i] * feats[i * d + j];
  }
}

// dbeta_i = df . feats[i * d ..].
template <typename S>
ENDORECON_HD void BlendWeightGradient(const S* df, const S* feats, int g, int d, S* dbeta) {
  for (int i = 0; i < g; ++i) {
    S dot = S(0);
    for (int j = 0; j < d; ++j) dot += df[j] * feats[i * d + j];
    dbeta[i] = dot;
  }
}

}  // namespace endorecon::field
