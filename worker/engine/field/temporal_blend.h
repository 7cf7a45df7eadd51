// The temporal blend weights of the grid ensemble: beta_t = softmax(MLP(t)), which GridEnsemble applies
// as f = sum_i beta_t^(i) f^(i). The network is 1 -> hidden (ReLU) -> G logits, as the paper's "small
// network of t". We chose it over a per-frame table of logits: it costs ~(hidden * (G + 1))
// multiply-adds per sample, nothing beside the heads, and it gives held-out times a value shaped by
// their neighbours rather than a table slot that was never trained. Its output layer starts at zero,
// so training starts from an even blend. A module of the field (module.h).
#pragma once

#include <cstddef>
#include <cstdint>

#include "worker/engine/field/batch_loop.h"
#include "worker/engine/field/mlp.h"
#include "worker/engine/field/module.h"

namespace endorecon::field {

template <typename S>
class TemporalBlend {
 public:
  struct Inputs {
    int n = 0;
    const S* time = nullptr;  // n
  };
  struct Outputs {
    S* hidden = nullptr;  // n x hidden_dim()
    S* beta = nullptr;    // n x G, rows sum to 1
  };
  struct OutputGrads {
    const S* dbeta = nullptr;  // n x G
  };
  struct InputGrads {};  // times are data: no gradient

  TemporalBlend(int grids, int hidden);

  int grids() const { return grids_; }
  int hidden_dim() const { return mlp_.hidden_dim(0); }
  std::size_t param_count() const { return mlp_.param_count(); }
  const Mlp<S>& mlp() const { return mlp_; }

  void Init(S* params, std::uint64_t seed) const;

  void Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass& pass);
  void Backward(const S* params, const Inputs& in, const Outputs& out, const OutputGrads& grad, S* dparams,
                const InputGrads& din, const DropoutPass& pass);

 private:
  int grids_;
  Mlp<S> mlp_;
  AlignedVector<S> dlogits_;  // n x G
};

}  // namespace endorecon::field
