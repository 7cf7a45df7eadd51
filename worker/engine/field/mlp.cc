// GCC 12 reports a false "maybe uninitialized" inside its own AVX-512 intrinsics when Eigen's GEMM
// kernels are inlined here; the warning is located in those headers, so it is silenced for this file.
#if !defined(__clang__)  // clang has no such warning, and refuses to ignore an unknown one
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif

#include "worker/engine/field/mlp.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <string>

#include "common/error.h"
#include "worker/engine/base/counter_rng.h"
#include "worker/engine/field/mlp_math.h"

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

static_assert(TrainableModule<Mlp<float>, float>);

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
    const base::CounterRng<S> rng(seed, (std::uint64_t{stream_} << 8) | static_cast<std::uint64_t>(k));
    for (std::size_t i = 0; i < count; ++i) {
      params[w_offset_[k] + i] = bound * (S(2) * rng(static_cast<std::uint32_t>(i)) - S(1));
    }
    std::fill_n(params + b_offset_[k], dims_[k + 1], S(0));
  }
}

template <typename S>
void Mlp<S>::ForwardTile(const S* params, const S* x, int rows, S* const* hidden, std::size_t row0, S* y,
                         const DropoutPass& pass) const {
  const int layers = static_cast<int>(dims_.size()) - 1;
  const bool dropout = pass.on && rate_ > 0;
  const S keep_scale = dropout ? S(1) / S(1 - rate_) : S(1);
  const auto threshold = static_cast<std::uint32_t>(std::min(rate_ * 4294967296.0, 4294967295.0));
  const std::uint32_t first_row = pass.first_row + static_cast<std::uint32_t>(row0);
  for (int k = 0; k < layers; ++k) {
    const int n_in = dims_[k], n_out = dims_[k + 1];
    S* out = k == layers - 1 ? y + row0 * n_out : hidden[k] + row0 * n_out;
    MutMap<S> Y(out, rows, n_out);
    Y.noalias() = ConstMap<S>(x, rows, n_in) * ConstMap<S>(params + w_offset_[k], n_in, n_out);
    Y.rowwise() += Eigen::Map<const RowVector<S>>(params + b_offset_[k], n_out);
    if (k == layers - 1) break;
    const HiddenDropout<S> drop =
        dropout ? HiddenDropout<S>{true,
                                   MakeDropoutKey(pass.seed, (stream_ << 4) | static_cast<std::uint32_t>(k)),
                                   threshold, keep_scale}
                : HiddenDropout<S>{};
    for (int r = 0; r < rows; ++r) {
      S* row = out + static_cast<std::size_t>(r) * n_out;
      for (int j = 0; j < n_out; ++j)
        row[j] = HiddenActivation(row[j], drop, first_row + std::uint32_t(r), n_out, j);
    }
    x = out;
  }
}

template <typename S>
void Mlp<S>::BackwardTile(const S* params, const S* x_in, int rows, S* const* hidden, std::size_t row0,
                          const S* dy, S* dx, S* dparams, bool dropout_on, S* scratch) const {
  const int layers = static_cast<int>(dims_.size()) - 1;
  const S keep_scale = (dropout_on && rate_ > 0) ? S(1) / S(1 - rate_) : S(1);
  const std::size_t stride = static_cast<std::size_t>(rows) * max_width();
  const S* g = dy;
  for (int k = layers - 1; k >= 0; --k) {
    const int n_in = dims_[k], n_out = dims_[k + 1];
    const S* x = k == 0 ? x_in : hidden[k - 1] + row0 * n_in;
    ConstMap<S> G(g, rows, n_out);
    MutMap<S>(dparams + w_offset_[k], n_in, n_out).noalias() += ConstMap<S>(x, rows, n_in).transpose() * G;
    Eigen::Map<RowVector<S>>(dparams + b_offset_[k], n_out) += G.colwise().sum();
    if (k == 0 && dx == nullptr) break;
    S* d = k == 0 ? dx : scratch + (k % 2) * stride;
    MutMap<S>(d, rows, n_in).noalias() = G * ConstMap<S>(params + w_offset_[k], n_in, n_out).transpose();
    if (k > 0) {
      const std::size_t count = static_cast<std::size_t>(rows) * n_in;
      for (std::size_t i = 0; i < count; ++i) d[i] = HiddenActivationGrad(x[i], d[i], keep_scale);
    }
    g = d;
  }
}

template <typename S>
void Mlp<S>::Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass& pass) {
  ParallelTasks(in.n, kTileRows, [&](int, int row0, int rows) {
    const std::size_t r = static_cast<std::size_t>(row0);
    ForwardTile(params, in.x + r * in_dim(), rows, out.hidden, r, out.y, pass);
  });
}

template <typename S>
void Mlp<S>::Backward(const S* params, const Inputs& in, const Outputs& out, const OutputGrads& grad,
                      S* dparams, const InputGrads& din, const DropoutPass& pass) {
  partials_.Reset(TaskCount(in.n, kTaskRows), param_count_);
  ParallelTasks(in.n, kTaskRows, [&](int task, int row0, int rows) {
    auto& scratch = scratch_.local();
    GrowTo(scratch, 2 * static_cast<std::size_t>(kTileRows) * max_width());
    ForTiles(rows, [&](int offset, int tile_rows) {
      const std::size_t r = static_cast<std::size_t>(row0 + offset);
      BackwardTile(params, in.x + r * in_dim(), tile_rows, out.hidden, r, grad.dy + r * out_dim(),
                   din.dx ? din.dx + r * in_dim() : nullptr, partials_.task(task), pass.on, scratch.data());
    });
  });
  partials_.AddTo(dparams);
}

template class Mlp<float>;
template class Mlp<double>;

}  // namespace endorecon::field
