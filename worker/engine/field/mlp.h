// A small fully connected network on batch-major arrays: in -> hidden... -> out, ReLU after every
// hidden layer (then inverted dropout when asked), nothing after the output layer. Each layer is one
// small GEMM, Y[rows x out] = X[rows x in] W[in x out] + b, on Eigen row-major maps.
// The object holds only the shape; parameters, gradients and activations live in caller arrays, so a
// Field keeps all of a group's parameters in one block and the same object serves any thread.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace endorecon::field {

// Dropout of one forward pass: `on` switches it for the pass; the mask is a pure function of
// (seed, the network's stream, layer, first_row + r, unit), see dropout.h.
struct DropoutPass {
  bool on = false;
  std::uint64_t seed = 0;
  std::uint32_t first_row = 0;  // index of the tile's first row within the whole batch
};

template <typename S>
class Mlp {
 public:
  // `stream` separates the dropout masks of different networks driven by the same seed.
  // Throws Error(kInvalidArgument) for a non-positive width or a rate outside [0, 1).
  Mlp(int in_dim, std::vector<int> hidden, int out_dim, double dropout_rate, std::uint32_t stream);

  int in_dim() const { return dims_.front(); }
  int out_dim() const { return dims_.back(); }
  int hidden_layers() const { return static_cast<int>(dims_.size()) - 2; }
  int hidden_dim(int k) const { return dims_[k + 1]; }
  int max_width() const;  // widest layer, inputs and outputs included
  // Values of scratch Backward needs for `rows` rows.
  std::size_t scratch_size(int rows) const;
  double dropout_rate() const { return rate_; }
  std::size_t param_count() const { return param_count_; }
  // Multiply-adds per sample in Forward (Backward does twice as many).
  std::size_t macs_per_sample() const;

  // Weights uniform in +-sqrt(6 / fan_in) (Kaiming, for ReLU), the output layer's scaled by
  // `output_gain`; biases zero.
  void Init(S* params, std::uint64_t seed, S output_gain = S(1)) const;

  // Forward of `rows` samples. in: rows x in_dim. hidden[k]: rows x hidden_dim(k), receives hidden layer
  // k after ReLU and dropout (kept for Backward). out: rows x out_dim.
  void Forward(const S* params, const S* in, int rows, S* const* hidden, S* out,
               const DropoutPass& drop) const;

  // Backward of the same rows given dout = dL/dout (rows x out_dim). Adds dL/dparams to grads; writes
  // dL/din (rows x in_dim) when din is not null. scratch: scratch_size(rows) values.
  // `dropout_on` must match the forward pass (the mask itself is read back from the zeros in hidden).
  void Backward(const S* params, const S* in, int rows, const S* const* hidden, const S* dout, S* din,
                S* grads, S* scratch, bool dropout_on) const;

 private:
  std::vector<int> dims_;  // in, hidden..., out
  std::vector<std::size_t> w_offset_, b_offset_;
  std::size_t param_count_ = 0;
  double rate_ = 0;
  std::uint32_t stream_ = 0;
};

}  // namespace endorecon::field
