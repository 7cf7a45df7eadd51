// The two heads of the field, each an Mlp with dropout in its hidden layers plus output activations:
//  density: MLP_dense(f) -> raw (2 + geo): mu_sigma = TruncExp(raw0), l_sigma = raw1, geometry
//           features = raw[2..] (no activation);
//  colour:  MLP_color([geo, SH(d), time features]) -> raw (4): mu_c = sigmoid(raw0..2), l_c = raw3.
// The log-variances are raw; their variances are VarianceFromLogVar (variance.h), applied by the loss.
// Both are modules of the field (module.h).
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

#include "worker/engine/field/batch_loop.h"
#include "worker/engine/field/mlp.h"
#include "worker/engine/field/module.h"

namespace endorecon::field {

// The most time frequencies the colour head takes (2^7 pi t: a period of 1/64 of the clip).
inline constexpr int kMaxTimeFrequencies = 8;

struct HeadsConfig {
  std::vector<int> density_hidden = {64};
  std::vector<int> color_hidden = {64, 64};
  int geo_features = 15;
  double dropout = 0.1;  // rate in both heads' hidden layers (when a pass turns dropout on)
  // The colour head's own rate; negative: `dropout`. The colour variances carry the uncertainty
  // score, and the density head's dropout is what costs geometry (docs/benchmarks.md).
  double color_dropout = -1;
  double ColorDropout() const { return color_dropout < 0 ? dropout : color_dropout; }
  // Frequencies of the sample's time in the colour head's input (heads_math.h, ColorInput); 0: the
  // colour depends on the time only through the features (the blend and the deformation).
  int color_time_frequencies = 0;
};

template <typename S>
class DensityHead {
 public:
  struct Inputs {
    int n = 0;
    const S* feat = nullptr;  // n x in_dim
  };
  struct Outputs {
    S* const* hidden = nullptr;  // the network's hidden layers (Mlp::Outputs)
    S* raw = nullptr;            // n x raw_dim(): the network's output, geometry features in columns 2..
    S* sigma = nullptr;          // n
    S* logvar = nullptr;         // n
  };
  struct OutputGrads {
    const S* dsigma = nullptr;   // n
    const S* dlogvar = nullptr;  // n
    const S* dgeo = nullptr;     // n x geo_features
  };
  struct InputGrads {
    S* dfeat = nullptr;  // n x in_dim
  };

  DensityHead(int in_dim, const HeadsConfig& config);

  const Mlp<S>& mlp() const { return mlp_; }
  int raw_dim() const { return mlp_.out_dim(); }
  std::size_t param_count() const { return mlp_.param_count(); }
  void Init(S* params, std::uint64_t seed) const { mlp_.Init(params, seed); }

  void Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass& pass);
  void Backward(const S* params, const Inputs& in, const Outputs& out, const OutputGrads& grad, S* dparams,
                const InputGrads& din, const DropoutPass& pass);

 private:
  int geo_;
  Mlp<S> mlp_;
  AlignedVector<S> draw_;  // n x raw_dim: dL/draw
};

template <typename S>
class ColorHead {
 public:
  struct Inputs {
    int n = 0;
    const S* geo = nullptr;  // row i at geo + i * geo_stride (the density head's raw columns 2..)
    int geo_stride = 0;
    const S* dir = nullptr;   // n x 3 unit view directions
    const S* time = nullptr;  // n; read only with time frequencies
  };
  struct Outputs {
    S* in = nullptr;             // n x in_dim(): the network input [geo, SH(dir), time features]
    S* const* hidden = nullptr;  // the network's hidden layers (Mlp::Outputs)
    S* raw = nullptr;            // n x 4
    S* rgb = nullptr;            // n x 3
    S* logvar = nullptr;         // n
  };
  struct OutputGrads {
    const S* drgb = nullptr;     // n x 3
    const S* dlogvar = nullptr;  // n
  };
  struct InputGrads {
    S* dgeo = nullptr;  // n x geo_features
  };

  explicit ColorHead(const HeadsConfig& config);

  const Mlp<S>& mlp() const { return mlp_; }
  int in_dim() const { return mlp_.in_dim(); }  // geo + 16 + 2 * time frequencies
  int time_frequencies() const { return time_frequencies_; }
  std::size_t param_count() const { return mlp_.param_count(); }
  void Init(S* params, std::uint64_t seed) const { mlp_.Init(params, seed); }

  void Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass& pass);
  void Backward(const S* params, const Inputs& in, const Outputs& out, const OutputGrads& grad, S* dparams,
                const InputGrads& din, const DropoutPass& pass);

 private:
  int geo_;
  int time_frequencies_;
  Mlp<S> mlp_;
  AlignedVector<S> draw_, din_;  // n x 4: dL/draw; n x in_dim: dL/din
};

}  // namespace endorecon::field
