// GCC 12 reports a false "maybe uninitialized" inside its own AVX-512 intrinsics when Eigen's GEMM
// kernels are inlined here; the warning is located in those headers, so it is silenced for this file.
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"

#include "worker/engine/field/mlp.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.h"
#include "worker/engine/field/dropout.h"
#include "worker/engine/render/rng.h"

namespace endorecon::field {
namespace {

template <typename S>
using RowMatrix = Eigen::Matrix<S, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
template <typename S>
using ConstMap = Eigen::Map<const RowMatrix<S>>;
template <typename S>
using MutMap = Eigen::Map<RowMatrix<S>>;
template <typename S>
using RowVector = Eigen::Matrix<S, 1, Eigen::Dynamic>;

}  // namespace

template <typename S>
Mlp<S>::Mlp(int in_dim, std::vector<int> hidden, int out_dim, double dropout_rate, std::uint32_t stream)
    : rate_(dropout_rate), stream_(stream) {
  dims_.push_back(in_dim);
  dims_.insert(dims_.end(), hidden.begin(), hidden.end());
  dims_.push_back(out_dim);
  for (int d : dims_) {
    if (d <= 0) FailInvalid("MLP layer width must be positive, got " + std::to_string(d));
  }
  if (!(dropout_rate >= 0 && dropout_rate < 1)) {
    FailInvalid("MLP dropout rate must be in [0, 1), got " + std::to_string(dropout_rate));
  }
  for (std::size_t k = 0; k + 1 < dims_.size(); ++k) {
    w_offset_.push_back(param_count_);
    param_count_ += static_cast<std::size_t>(dims_[k]) * dims_[k + 1];
    b_offset_.push_back(param_count_);
    param_count_ += dims_[k + 1];
  }
}

template <typename S>
int Mlp<S>::max_width() const {
  return *std::max_element(dims_.begin(), dims_.end());
}

template <typename S>
std::size_t Mlp<S>::scratch_size(int rows) const {
  return 2 * static_cast<std::size_t>(rows) * max_width();
}

template <typename S>
std::size_t Mlp<S>::macs_per_sample() const {
  std::size_t macs = 0;
  for (std::size_t k = 0; k + 1 < dims_.size(); ++k)
    macs += static_cast<std::size_t>(dims_[k]) * dims_[k + 1];
  return macs;
}

template <typename S>
void Mlp<S>::Init(S* params, std::uint64_t seed, S output_gain) const {
  const int layers = static_cast<int>(dims_.size()) - 1;
  for (int k = 0; k < layers; ++k) {
    const S bound = std::sqrt(S(6) / S(dims_[k])) * (k == layers - 1 ? output_gain : S(1));
    const std::size_t count = static_cast<std::size_t>(dims_[k]) * dims_[k + 1];
    const render::CounterRng<S> rng(seed, (std::uint64_t{stream_} << 8) | static_cast<std::uint64_t>(k));
    for (std::size_t i = 0; i < count; ++i) {
      params[w_offset_[k] + i] = bound * (S(2) * rng(static_cast<std::uint32_t>(i)) - S(1));
    }
    std::fill_n(params + b_offset_[k], dims_[k + 1], S(0));
  }
}

template <typename S>
void Mlp<S>::Forward(const S* params, const S* in, int rows, S* const* hidden, S* out,
                     const DropoutPass& drop) const {
  const int layers = static_cast<int>(dims_.size()) - 1;
  const bool dropout = drop.on && rate_ > 0;
  const S keep_scale = dropout ? S(1) / S(1 - rate_) : S(1);
  const auto threshold = static_cast<std::uint32_t>(std::min(rate_ * 4294967296.0, 4294967295.0));
  const S* x = in;
  for (int k = 0; k < layers; ++k) {
    const int n_in = dims_[k], n_out = dims_[k + 1];
    S* y = k == layers - 1 ? out : hidden[k];
    MutMap<S> Y(y, rows, n_out);
    Y.noalias() = ConstMap<S>(x, rows, n_in) * ConstMap<S>(params + w_offset_[k], n_in, n_out);
    Y.rowwise() += Eigen::Map<const RowVector<S>>(params + b_offset_[k], n_out);
    if (k == layers - 1) break;
    if (dropout) {
      const DropoutKey key = MakeDropoutKey(drop.seed, (stream_ << 4) | static_cast<std::uint32_t>(k));
      for (int r = 0; r < rows; ++r) {
        S* row = y + static_cast<std::size_t>(r) * n_out;
        const std::uint32_t base =
            (drop.first_row + static_cast<std::uint32_t>(r)) * static_cast<std::uint32_t>(n_out);
        for (int j = 0; j < n_out; ++j) {
          const bool keep = DropoutKeep(key, base + static_cast<std::uint32_t>(j), threshold);
          row[j] = (keep && row[j] > S(0)) ? row[j] * keep_scale : S(0);
        }
      }
    } else {
      const std::size_t count = static_cast<std::size_t>(rows) * n_out;
      for (std::size_t i = 0; i < count; ++i) y[i] = y[i] > S(0) ? y[i] : S(0);
    }
    x = y;
  }
}

template <typename S>
void Mlp<S>::Backward(const S* params, const S* in, int rows, const S* const* hidden, const S* dout, S* din,
                      S* grads, S* scratch, bool dropout_on) const {
  const int layers = static_cast<int>(dims_.size()) - 1;
  const S keep_scale = (dropout_on && rate_ > 0) ? S(1) / S(1 - rate_) : S(1);
  const std::size_t stride = static_cast<std::size_t>(rows) * max_width();
  const S* g = dout;
  for (int k = layers - 1; k >= 0; --k) {
    const int n_in = dims_[k], n_out = dims_[k + 1];
    const S* x = k == 0 ? in : hidden[k - 1];
    ConstMap<S> G(g, rows, n_out);
    MutMap<S>(grads + w_offset_[k], n_in, n_out).noalias() += ConstMap<S>(x, rows, n_in).transpose() * G;
    Eigen::Map<RowVector<S>>(grads + b_offset_[k], n_out) += G.colwise().sum();
    if (k == 0 && din == nullptr) break;
    S* dx = k == 0 ? din : scratch + (k % 2) * stride;
    MutMap<S>(dx, rows, n_in).noalias() = G * ConstMap<S>(params + w_offset_[k], n_in, n_out).transpose();
    if (k > 0) {
      const std::size_t count = static_cast<std::size_t>(rows) * n_in;
      for (std::size_t i = 0; i < count; ++i) dx[i] = x[i] > S(0) ? dx[i] * keep_scale : S(0);
    }
    g = dx;
  }
}

template class Mlp<float>;
template class Mlp<double>;

}  // namespace endorecon::field
