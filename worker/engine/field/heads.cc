#include "worker/engine/field/heads.h"

#include <algorithm>

#include "worker/engine/field/hash_math.h"
#include "worker/engine/field/sh_encoding.h"

namespace endorecon::field {
namespace {

constexpr std::uint32_t kDensityStream = 0xd1u;
constexpr std::uint32_t kColorStream = 0xc2u;

}  // namespace

template <typename S>
DensityHead<S>::DensityHead(int in_dim, const HeadsConfig& config)
    : geo_(config.geo_features),
      mlp_(in_dim, config.density_hidden, 2 + config.geo_features, config.dropout, kDensityStream) {}

template <typename S>
void DensityHead<S>::Forward(const S* params, const S* feat, int n, S* const* hidden, S* raw, S* sigma,
                             S* logvar, const DropoutPass& drop) const {
  mlp_.Forward(params, feat, n, hidden, raw, drop);
  const int w = raw_dim();
  for (int i = 0; i < n; ++i) {
    sigma[i] = TruncExp(raw[static_cast<std::size_t>(i) * w]);
    logvar[i] = raw[static_cast<std::size_t>(i) * w + 1];
  }
}

template <typename S>
std::size_t DensityHead<S>::scratch_size(int n) const {
  return static_cast<std::size_t>(n) * raw_dim() + mlp_.scratch_size(n);
}

template <typename S>
void DensityHead<S>::Backward(const S* params, const S* feat, int n, const S* const* hidden, const S* raw,
                              const S* dsigma, const S* dlogvar, const S* dgeo, S* dfeat, S* grads,
                              S* scratch, bool dropout_on) const {
  const int w = raw_dim();
  S* draw = scratch;
  for (int i = 0; i < n; ++i) {
    S* d = draw + static_cast<std::size_t>(i) * w;
    d[0] = dsigma ? dsigma[i] * TruncExpGrad(raw[static_cast<std::size_t>(i) * w]) : S(0);
    d[1] = dlogvar ? dlogvar[i] : S(0);
    if (dgeo) {
      std::copy_n(dgeo + static_cast<std::size_t>(i) * geo_, geo_, d + 2);
    } else {
      std::fill_n(d + 2, geo_, S(0));
    }
  }
  mlp_.Backward(params, feat, n, hidden, draw, dfeat, grads, scratch + static_cast<std::size_t>(n) * w,
                dropout_on);
}

template <typename S>
ColorHead<S>::ColorHead(const HeadsConfig& config)
    : geo_(config.geo_features),
      mlp_(config.geo_features + kShDims, config.color_hidden, 4, config.ColorDropout(), kColorStream) {}

template <typename S>
void ColorHead<S>::Input(const S* geo, int geo_stride, const S* dir, int n, S* in) const {
  const int w = in_dim();
  for (int i = 0; i < n; ++i) {
    S* row = in + static_cast<std::size_t>(i) * w;
    std::copy_n(geo + static_cast<std::size_t>(i) * geo_stride, geo_, row);
    ShEncode(dir + 3 * i, row + geo_);
  }
}

template <typename S>
void ColorHead<S>::Forward(const S* params, const S* geo, int geo_stride, const S* dir, int n, S* in,
                           S* const* hidden, S* raw, S* rgb, S* logvar, const DropoutPass& drop) const {
  Input(geo, geo_stride, dir, n, in);
  mlp_.Forward(params, in, n, hidden, raw, drop);
  for (int i = 0; i < n; ++i) {
    const S* r = raw + 4 * static_cast<std::size_t>(i);
    for (int c = 0; c < 3; ++c) rgb[3 * i + c] = Sigmoid(r[c]);
    logvar[i] = r[3];
  }
}

template <typename S>
std::size_t ColorHead<S>::scratch_size(int n) const {
  return static_cast<std::size_t>(n) * (4 + in_dim()) + mlp_.scratch_size(n);
}

template <typename S>
void ColorHead<S>::Backward(const S* params, const S* in, int n, const S* const* hidden, const S* raw,
                            const S* drgb, const S* dlogvar, S* dgeo, S* grads, S* scratch,
                            bool dropout_on) const {
  S* draw = scratch;
  S* din = scratch + 4 * static_cast<std::size_t>(n);
  for (int i = 0; i < n; ++i) {
    const S* r = raw + 4 * static_cast<std::size_t>(i);
    S* d = draw + 4 * static_cast<std::size_t>(i);
    for (int c = 0; c < 3; ++c) {
      const S s = Sigmoid(r[c]);
      d[c] = drgb ? drgb[3 * i + c] * s * (S(1) - s) : S(0);
    }
    d[3] = dlogvar ? dlogvar[i] : S(0);
  }
  const int w = in_dim();
  mlp_.Backward(params, in, n, hidden, draw, dgeo ? din : nullptr, grads,
                din + static_cast<std::size_t>(n) * w, dropout_on);
  if (!dgeo) return;
  for (int i = 0; i < n; ++i)
    std::copy_n(din + static_cast<std::size_t>(i) * w, geo_, dgeo + static_cast<std::size_t>(i) * geo_);
}

template class DensityHead<float>;
template class DensityHead<double>;
template class ColorHead<float>;
template class ColorHead<double>;

}  // namespace endorecon::field
