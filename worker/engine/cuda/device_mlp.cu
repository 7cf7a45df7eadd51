#include <algorithm>

#include "worker/engine/cuda/device_mlp.h"
#include "worker/engine/cuda/launch.cuh"
#include "worker/engine/field/mlp_math.h"

namespace endorecon::cuda {
namespace {

// The weight gradient's threads: each sums one entry over a chunk of rows, with enough chunks that
// a layer's entries make at least kWeightGradThreads threads (a small layer summed over long chunks
// left most of the device idle: the blend MLP's 39 blocks took 34 us of an H200's step), each chunk
// of at least kMinRowsPerChunk rows (the chunks' sums meet in one atomic add each).
constexpr std::size_t kWeightGradThreads = std::size_t{1} << 17;
constexpr std::size_t kMinRowsPerChunk = 16;

// A layer's weights fit the input gradient's shared memory when n_in x n_out floats take at most
// this many (32 KB; larger layers read them from global memory).
constexpr int kMaxSharedWeights = 8192;
constexpr unsigned kInputGradBlocks = 2048;  // more than a V100's or an H200's SMs hold at once

__global__ void LayerForwardKernel(const float* x, int n, int n_in, const float* w, const float* b, float* y,
                                   int n_out, bool hidden, field::HiddenDropout<float> drop,
                                   std::uint32_t first_row) {
  const std::size_t i = ThreadIndex();
  if (i >= static_cast<std::size_t>(n) * n_out) return;
  const std::size_t row = i / n_out;
  const int j = static_cast<int>(i % n_out);
  float acc = b[j];
  const float* xr = x + row * n_in;
  for (int k = 0; k < n_in; ++k) acc += xr[k] * w[static_cast<std::size_t>(k) * n_out + j];
  if (hidden) acc = field::HiddenActivation(acc, drop, first_row + static_cast<std::uint32_t>(row), n_out, j);
  y[i] = acc;
}

// dx = (dy W^T), times the hidden activation's gradient when x_prev (the layer's input, a hidden
// activation) is given. A warp's threads are consecutive inputs k of one or two rows, so W's row k
// (w[k * n_out + j] for j < n_out) differs from lane to lane: with kShared the block first copies W
// transposed into shared memory (wt[j * n_in + k], neighbouring lanes in neighbouring banks), where
// from global memory each of the n_out loads of a warp touched 32 cache lines (the colour MLP's input
// gradient took 130 us of an H200's 0.8 ms step). Its threads loop over the rows (at most
// kInputGradBlocks blocks), so a block copies W once for many rows.
template <bool kShared>
__global__ void LayerInputGradKernel(const float* dy, int n, int n_out, const float* w, int n_in,
                                     const float* x_prev, float keep_scale, float* dx) {
  extern __shared__ float wt[];
  if constexpr (kShared) {
    for (int e = static_cast<int>(threadIdx.x); e < n_in * n_out; e += static_cast<int>(blockDim.x)) {
      wt[(e % n_out) * n_in + e / n_out] = w[e];
    }
    __syncthreads();
  }
  const std::size_t total = static_cast<std::size_t>(n) * n_in;
  for (std::size_t i = ThreadIndex(); i < total; i += static_cast<std::size_t>(gridDim.x) * blockDim.x) {
    const std::size_t row = i / n_in;
    const int k = static_cast<int>(i % n_in);
    float acc = 0.0f;
    const float* g = dy + row * n_out;
    if constexpr (kShared) {
      for (int j = 0; j < n_out; ++j) acc += g[j] * wt[j * n_in + k];
    } else {
      const float* wk = w + static_cast<std::size_t>(k) * n_out;
      for (int j = 0; j < n_out; ++j) acc += g[j] * wk[j];
    }
    dx[i] = x_prev ? field::HiddenActivationGrad(x_prev[i], acc, keep_scale) : acc;
  }
}

// dW += x^T dy and db += column sums of dy, each thread over one chunk of `rows_per_chunk` rows.
__global__ void LayerWeightGradKernel(const float* x, const float* dy, int n, int n_in, int n_out,
                                      std::size_t rows_per_chunk, float* dw, float* db) {
  const std::size_t per_chunk = static_cast<std::size_t>(n_in) * n_out + n_out;
  const std::size_t i = ThreadIndex();
  const std::size_t chunks = (static_cast<std::size_t>(n) + rows_per_chunk - 1) / rows_per_chunk;
  if (i >= chunks * per_chunk) return;
  const std::size_t chunk = i / per_chunk, e = i % per_chunk;
  const std::size_t row0 = chunk * rows_per_chunk;
  const std::size_t row1 = row0 + rows_per_chunk < static_cast<std::size_t>(n) ? row0 + rows_per_chunk : n;
  float sum = 0.0f;
  if (e < static_cast<std::size_t>(n_in) * n_out) {
    const std::size_t k = e / n_out, j = e % n_out;
    for (std::size_t r = row0; r < row1; ++r) sum += x[r * n_in + k] * dy[r * n_out + j];
    atomicAdd(dw + e, sum);
  } else {
    const std::size_t j = e - static_cast<std::size_t>(n_in) * n_out;
    for (std::size_t r = row0; r < row1; ++r) sum += dy[r * n_out + j];
    atomicAdd(db + j, sum);
  }
}

field::HiddenDropout<float> DropoutOf(const field::DropoutPass& pass, double rate, std::uint32_t stream,
                                      int layer) {
  if (!pass.on || rate <= 0) return {};
  return {true, field::MakeDropoutKey(pass.seed, (stream << 4) | static_cast<std::uint32_t>(layer)),
          static_cast<std::uint32_t>(std::min(rate * 4294967296.0, 4294967295.0)),
          static_cast<float>(1.0 / (1.0 - rate))};
}

}  // namespace

DeviceMlp::DeviceMlp(const field::Mlp<float>& layout)
    : rate_(layout.dropout_rate()), stream_(layout.stream()) {
  dims_.push_back(layout.in_dim());
  for (int k = 0; k < layout.hidden_layers(); ++k) dims_.push_back(layout.hidden_dim(k));
  dims_.push_back(layout.out_dim());
  for (std::size_t k = 0; k + 1 < dims_.size(); ++k) {
    w_offset_.push_back(layout.weight_offset(static_cast<int>(k)));
    b_offset_.push_back(layout.bias_offset(static_cast<int>(k)));
  }
}

std::size_t DeviceMlp::scratch_size(int n) const {
  return 2 * static_cast<std::size_t>(n) * *std::max_element(dims_.begin(), dims_.end());
}

void DeviceMlp::Forward(const float* params, const float* x, int n, float* const* hidden, float* y,
                        const field::DropoutPass& pass) const {
  if (n <= 0) return;
  const int layers = static_cast<int>(dims_.size()) - 1;
  for (int k = 0; k < layers; ++k) {
    const int n_in = dims_[k], n_out = dims_[k + 1];
    const bool is_hidden = k < layers - 1;
    float* out = is_hidden ? hidden[k] : y;
    LayerForwardKernel<<<Blocks(static_cast<std::size_t>(n) * n_out), kThreads>>>(
        x, n, n_in, params + w_offset_[k], params + b_offset_[k], out, n_out, is_hidden,
        DropoutOf(pass, rate_, stream_, k), pass.first_row);
    CheckLaunch("MLP layer forward kernel");
    x = out;
  }
}

void DeviceMlp::Backward(const float* params, const float* x, int n, float* const* hidden, const float* dy,
                         float* dx, float* dparams, float* scratch, const field::DropoutPass& pass) const {
  if (n <= 0) return;
  const int layers = static_cast<int>(dims_.size()) - 1;
  const float keep_scale = pass.on && rate_ > 0 ? static_cast<float>(1.0 / (1.0 - rate_)) : 1.0f;
  const std::size_t stride = scratch_size(n) / 2;
  const float* g = dy;
  for (int k = layers - 1; k >= 0; --k) {
    const int n_in = dims_[k], n_out = dims_[k + 1];
    const float* in = k == 0 ? x : hidden[k - 1];
    const std::size_t entries = static_cast<std::size_t>(n_in) * n_out + n_out;
    const std::size_t chunks = std::max<std::size_t>(1, (kWeightGradThreads + entries - 1) / entries);
    const std::size_t rows_per_chunk =
        std::max(kMinRowsPerChunk, (static_cast<std::size_t>(n) + chunks - 1) / chunks);
    const std::size_t used = (static_cast<std::size_t>(n) + rows_per_chunk - 1) / rows_per_chunk;
    LayerWeightGradKernel<<<Blocks(used * entries), kThreads>>>(
        in, g, n, n_in, n_out, rows_per_chunk, dparams + w_offset_[k], dparams + b_offset_[k]);
    CheckLaunch("MLP weight gradient kernel");
    if (k == 0 && dx == nullptr) break;
    float* d = k == 0 ? dx : scratch + (k % 2) * stride;
    const unsigned blocks = std::min(kInputGradBlocks, Blocks(static_cast<std::size_t>(n) * n_in));
    const float* x_prev = k > 0 ? hidden[k - 1] : nullptr;
    if (n_in * n_out <= kMaxSharedWeights) {
      LayerInputGradKernel<true><<<blocks, kThreads, sizeof(float) * n_in * n_out>>>(
          g, n, n_out, params + w_offset_[k], n_in, x_prev, keep_scale, d);
    } else {
      LayerInputGradKernel<false>
          <<<blocks, kThreads>>>(g, n, n_out, params + w_offset_[k], n_in, x_prev, keep_scale, d);
    }
    CheckLaunch("MLP input gradient kernel");
    g = d;
  }
}

}  // namespace endorecon::cuda
