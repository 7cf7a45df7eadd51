// The two heads of the field, each an Mlp with dropout in its hidden layers plus output activations:
//  density: MLP_dense(f) -> raw (2 + geo): mu_sigma = TruncExp(raw0), l_sigma = raw1, geometry
//           features = raw[2..] (no activation);
//  colour:  MLP_color([geo, SH(d)]) -> raw (4): mu_c = sigmoid(raw0..2), l_c = raw3.
// The log-variances are raw; their variances are VarianceFromLogVar (variance.h), applied by the loss.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "worker/engine/field/mlp.h"

namespace endorecon::field {

struct HeadsConfig {
  std::vector<int> density_hidden = {64};
  std::vector<int> color_hidden = {64, 64};
  int geo_features = 15;
  double dropout = 0.1;  // rate in both heads' hidden layers (when a pass turns dropout on)
  // The colour head's own rate; negative: `dropout`. The colour variances carry the uncertainty
  // score, and the density head's dropout is what costs geometry (docs/benchmarks.md).
  double color_dropout = -1;
  double ColorDropout() const { return color_dropout < 0 ? dropout : color_dropout; }
};

template <typename S>
class DensityHead {
 public:
  DensityHead(int in_dim, const HeadsConfig& config);

  const Mlp<S>& mlp() const { return mlp_; }
  int raw_dim() const { return mlp_.out_dim(); }  // 2 + geo; geo features are raw columns 2..
  std::size_t param_count() const { return mlp_.param_count(); }
  void Init(S* params, std::uint64_t seed) const { mlp_.Init(params, seed); }

  // raw: n x raw_dim(), kept (it holds the geometry features); sigma, logvar: n values each.
  void Forward(const S* params, const S* feat, int n, S* const* hidden, S* raw, S* sigma, S* logvar,
               const DropoutPass& drop) const;

  // dsigma, dlogvar (n values) and dgeo (n x geo) may each be null (= zero). Writes dfeat (n x in_dim)
  // when not null. scratch: scratch_size(n) values.
  void Backward(const S* params, const S* feat, int n, const S* const* hidden, const S* raw, const S* dsigma,
                const S* dlogvar, const S* dgeo, S* dfeat, S* grads, S* scratch, bool dropout_on) const;
  std::size_t scratch_size(int n) const;

 private:
  int geo_;
  Mlp<S> mlp_;
};

template <typename S>
class ColorHead {
 public:
  explicit ColorHead(const HeadsConfig& config);

  const Mlp<S>& mlp() const { return mlp_; }
  int in_dim() const { return mlp_.in_dim(); }  // geo + 16
  std::size_t param_count() const { return mlp_.param_count(); }
  void Init(S* params, std::uint64_t seed) const { mlp_.Init(params, seed); }

  // The network input [geo, SH(dir)] of n samples into in (n x in_dim()); geo rows at geo + i * geo_stride.
  void Input(const S* geo, int geo_stride, const S* dir, int n, S* in) const;

  // geo: rows at geo + i * geo_stride; dir: n x 3 unit directions. in (n x in_dim()) receives the
  // network input [geo, SH(dir)] and raw (n x 4) its output, both kept for Backward;
  // rgb: n x 3, logvar: n values.
  void Forward(const S* params, const S* geo, int geo_stride, const S* dir, int n, S* in, S* const* hidden,
               S* raw, S* rgb, S* logvar, const DropoutPass& drop) const;

  // drgb (n x 3) and dlogvar (n) may be null (= zero). Writes dgeo (n x geo) when not null.
  // scratch: scratch_size(n) values.
  void Backward(const S* params, const S* in, int n, const S* const* hidden, const S* raw, const S* drgb,
                const S* dlogvar, S* dgeo, S* grads, S* scratch, bool dropout_on) const;
  std::size_t scratch_size(int n) const;

 private:
  int geo_;
  Mlp<S> mlp_;
};

}  // namespace endorecon::field
