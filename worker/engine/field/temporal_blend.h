// Temporal blending of the grid ensemble: f = sum_i beta_t^(i) f^(i), beta_t = softmax(MLP(t)).
// The network is 1 -> hidden (ReLU) -> G logits, as the paper's "small network of t". We chose it over
// a per-frame table of logits: it costs ~(hidden * (G + 1)) multiply-adds per sample, nothing beside
// the heads, and it gives held-out times a value shaped by their neighbours rather than a table slot
// that was never trained. Its output layer starts at zero, so training starts from an even blend.
#pragma once

#include <cstddef>
#include <cstdint>

#include "worker/engine/field/mlp.h"

namespace endorecon::field {

template <typename S>
class TemporalBlend {
 public:
  TemporalBlend(int grids, int feature_dim, int hidden);

  int grids() const { return grids_; }
  int feature_dim() const { return feature_dim_; }
  int hidden_dim() const { return mlp_.hidden_dim(0); }
  std::size_t param_count() const { return mlp_.param_count(); }
  const Mlp<S>& mlp() const { return mlp_; }

  void Init(S* params, std::uint64_t seed) const;

  // beta (n x G, rows sum to 1) of times t (n values); hidden (n x hidden_dim()) is kept for Backward.
  void Weights(const S* params, const S* t, int n, S* hidden, S* beta) const;

  // f (n x D) = sum_i beta_i f^(i), feats being n x (G * D) as GridEnsemble::Forward writes them.
  void Blend(const S* beta, const S* feats, int n, S* f) const;

  // Given df = dL/df (n x D): adds dL/dparams to grads; writes dL/dfeats = beta_i df (n x G * D) when
  // dfeats is not null. scratch: scratch_size(n) values.
  void Backward(const S* params, const S* t, int n, const S* hidden, const S* beta, const S* feats,
                const S* df, S* dfeats, S* grads, S* scratch) const;
  std::size_t scratch_size(int n) const;

 private:
  int grids_, feature_dim_;
  Mlp<S> mlp_;
};

}  // namespace endorecon::field
