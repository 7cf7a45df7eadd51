// A small fully connected network on batch-major arrays: in -> hidden... -> out, ReLU after every
// hidden layer (then inverted dropout when the pass asks for it), nothing after the output layer. Each
// layer of a tile of kTileRows rows is one small GEMM, Y[rows x out] = X[rows x in] W[in x out] + b, on
// Eigen row-major maps; a tile runs every layer before the next tile starts, so its activations stay
// in cache. A module of the field (module.h); the heads and the temporal blend are built on it.
#pragma once

#include <tbb/enumerable_thread_specific.h>

#include <cstddef>
#include <cstdint>
#include <vector>

#include "worker/engine/field/batch_loop.h"
#include "worker/engine/field/module.h"

namespace endorecon::field {

template <typename S>
class Mlp {
 public:
  struct Inputs {
    int n = 0;
    const S* x = nullptr;  // n x in_dim
  };
  struct Outputs {
    S* const* hidden = nullptr;  // hidden[k]: n x hidden_dim(k), after ReLU and dropout
    S* y = nullptr;              // n x out_dim
  };
  struct OutputGrads {
    const S* dy = nullptr;  // n x out_dim
  };
  struct InputGrads {
    S* dx = nullptr;  // n x in_dim
  };

  // `stream` separates the dropout masks of different networks driven by the same seed.
  // Throws Error(kInvalidArgument) for a non-positive width or a rate outside [0, 1).
  Mlp(int in_dim, std::vector<int> hidden, int out_dim, double dropout_rate, std::uint32_t stream);

  int in_dim() const { return dims_.front(); }
  int out_dim() const { return dims_.back(); }
  int hidden_layers() const { return static_cast<int>(dims_.size()) - 2; }
  int hidden_dim(int k) const { return dims_[k + 1]; }
  int max_width() const;  // widest layer, inputs and outputs included
  double dropout_rate() const { return rate_; }
  std::uint32_t stream() const { return stream_; }
  std::size_t param_count() const { return param_count_; }
  // Layer k's weights (in x out, row-major) and biases within the parameter block.
  std::size_t weight_offset(int k) const { return w_offset_[k]; }
  std::size_t bias_offset(int k) const { return b_offset_[k]; }
  // Multiply-adds per sample in Forward (Backward does twice as many).
  std::size_t macs_per_sample() const;

  // Weights uniform in +-sqrt(6 / fan_in) (Kaiming, for ReLU), the output layer's scaled by
  // `output_gain`; biases zero.
  void Init(S* params, std::uint64_t seed) const { Init(params, seed, S(1)); }
  void Init(S* params, std::uint64_t seed, S output_gain) const;

  void Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass& pass);
  // The dropout mask is read back from the zeros in the kept hidden activations; pass.on must match
  // the forward pass (it decides the inverted-dropout scale).
  void Backward(const S* params, const Inputs& in, const Outputs& out, const OutputGrads& grad, S* dparams,
                const InputGrads& din, const DropoutPass& pass);

 private:
  // One tile: rows [row0, row0 + rows) of the batch.
  void ForwardTile(const S* params, const S* x, int rows, S* const* hidden, std::size_t row0, S* y,
                   const DropoutPass& pass) const;
  void BackwardTile(const S* params, const S* x, int rows, S* const* hidden, std::size_t row0, const S* dy,
                    S* dx, S* dparams, bool dropout_on, S* scratch) const;

  std::vector<int> dims_;  // in, hidden..., out
  std::vector<std::size_t> w_offset_, b_offset_;
  std::size_t param_count_ = 0;
  double rate_ = 0;
  std::uint32_t stream_ = 0;
  TaskPartials<S> partials_;
  tbb::enumerable_thread_specific<AlignedVector<S>> scratch_;  // a tile's backward scratch, per thread
};

}  // namespace endorecon::field
