#include "worker/engine/field/temporal_blend.h"

#include <algorithm>
#include <cmath>

namespace endorecon::field {

template <typename S>
TemporalBlend<S>::TemporalBlend(int grids, int feature_dim, int hidden)
    : grids_(grids), feature_dim_(feature_dim), mlp_(1, {hidden}, grids, 0.0, 0x7b1u) {}

template <typename S>
void TemporalBlend<S>::Init(S* params, std::uint64_t seed) const {
  mlp_.Init(params, seed, S(0));
}

template <typename S>
void TemporalBlend<S>::Weights(const S* params, const S* t, int n, S* hidden, S* beta) const {
  mlp_.Forward(params, t, n, &hidden, beta, DropoutPass{});
  for (int s = 0; s < n; ++s) {
    S* b = beta + static_cast<std::size_t>(s) * grids_;
    const S top = *std::max_element(b, b + grids_);
    S sum = S(0);
    for (int i = 0; i < grids_; ++i) sum += (b[i] = std::exp(b[i] - top));
    for (int i = 0; i < grids_; ++i) b[i] /= sum;
  }
}

template <typename S>
void TemporalBlend<S>::Blend(const S* beta, const S* feats, int n, S* f) const {
  const int d = feature_dim_;
  for (int s = 0; s < n; ++s) {
    const S* b = beta + static_cast<std::size_t>(s) * grids_;
    const S* in = feats + static_cast<std::size_t>(s) * grids_ * d;
    S* out = f + static_cast<std::size_t>(s) * d;
    for (int j = 0; j < d; ++j) out[j] = b[0] * in[j];
    for (int i = 1; i < grids_; ++i) {
      for (int j = 0; j < d; ++j) out[j] += b[i] * in[i * d + j];
    }
  }
}

template <typename S>
std::size_t TemporalBlend<S>::scratch_size(int n) const {
  return static_cast<std::size_t>(n) * grids_ + mlp_.scratch_size(n);
}

template <typename S>
void TemporalBlend<S>::Backward(const S* params, const S* t, int n, const S* hidden, const S* beta,
                                const S* feats, const S* df, S* dfeats, S* grads, S* scratch) const {
  const int d = feature_dim_;
  S* dlogits = scratch;
  for (int s = 0; s < n; ++s) {
    const S* b = beta + static_cast<std::size_t>(s) * grids_;
    const S* in = feats + static_cast<std::size_t>(s) * grids_ * d;
    const S* g = df + static_cast<std::size_t>(s) * d;
    S* dl = dlogits + static_cast<std::size_t>(s) * grids_;
    S mean = S(0);
    for (int i = 0; i < grids_; ++i) {
      S dot = S(0);
      for (int j = 0; j < d; ++j) dot += g[j] * in[i * d + j];
      dl[i] = dot;
      mean += b[i] * dot;
    }
    // Softmax backward: dlogit_i = beta_i (dbeta_i - sum_k beta_k dbeta_k).
    for (int i = 0; i < grids_; ++i) dl[i] = b[i] * (dl[i] - mean);
    if (dfeats) {
      S* out = dfeats + static_cast<std::size_t>(s) * grids_ * d;
      for (int i = 0; i < grids_; ++i) {
        for (int j = 0; j < d; ++j) out[i * d + j] = b[i] * g[j];
      }
    }
  }
  mlp_.Backward(params, t, n, &hidden, dlogits, nullptr, grads,
                scratch + static_cast<std::size_t>(n) * grids_, false);
}

template class TemporalBlend<float>;
template class TemporalBlend<double>;

}  // namespace endorecon::field
