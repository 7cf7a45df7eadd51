#include "worker/engine/field/heads.h"

#include <algorithm>

#include "worker/engine/field/activations.h"
#include "worker/engine/field/sh_encoding.h"

namespace endorecon::field {
namespace {

constexpr std::uint32_t kDensityStream = 0xd1u;
constexpr std::uint32_t kColorStream = 0xc2u;

}  // namespace

static_assert(TrainableModule<DensityHead<float>, float>);
static_assert(TrainableModule<ColorHead<float>, float>);

template <typename S>
DensityHead<S>::DensityHead(int in_dim, const HeadsConfig& config)
    : geo_(config.geo_features),
      mlp_(in_dim, config.density_hidden, 2 + config.geo_features, config.dropout, kDensityStream) {}

template <typename S>
void DensityHead<S>::Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass& pass) {
  mlp_.Forward(params, {in.n, in.feat}, {out.hidden, out.raw}, pass);
  const std::size_t w = static_cast<std::size_t>(raw_dim());
  ParallelRows(in.n, [&](std::size_t i) {
    out.sigma[i] = TruncExp(out.raw[i * w]);
    out.logvar[i] = out.raw[i * w + 1];
  });
}

template <typename S>
void DensityHead<S>::Backward(const S* params, const Inputs& in, const Outputs& out, const OutputGrads& grad,
                              S* dparams, const InputGrads& din, const DropoutPass& pass) {
  const std::size_t w = static_cast<std::size_t>(raw_dim());
  GrowTo(draw_, static_cast<std::size_t>(in.n) * w);
  ParallelRows(in.n, [&](std::size_t i) {
    S* d = draw_.data() + i * w;
    d[0] = grad.dsigma ? grad.dsigma[i] * TruncExpGrad(out.raw[i * w]) : S(0);
    d[1] = grad.dlogvar ? grad.dlogvar[i] : S(0);
    if (grad.dgeo) {
      std::copy_n(grad.dgeo + i * geo_, geo_, d + 2);
    } else {
      std::fill_n(d + 2, geo_, S(0));
    }
  });
  mlp_.Backward(params, {in.n, in.feat}, {out.hidden, out.raw}, {draw_.data()}, dparams, {din.dfeat}, pass);
}

template <typename S>
ColorHead<S>::ColorHead(const HeadsConfig& config)
    : geo_(config.geo_features),
      mlp_(config.geo_features + kShDims, config.color_hidden, 4, config.ColorDropout(), kColorStream) {}

template <typename S>
void ColorHead<S>::Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass& pass) {
  const std::size_t w = static_cast<std::size_t>(in_dim());
  ParallelRows(in.n, [&](std::size_t i) {
    S* row = out.in + i * w;
    std::copy_n(in.geo + i * in.geo_stride, geo_, row);
    ShEncode(in.dir + 3 * i, row + geo_);
  });
  mlp_.Forward(params, {in.n, out.in}, {out.hidden, out.raw}, pass);
  ParallelRows(in.n, [&](std::size_t i) {
    const S* r = out.raw + 4 * i;
    for (int c = 0; c < 3; ++c) out.rgb[3 * i + c] = Sigmoid(r[c]);
    out.logvar[i] = r[3];
  });
}

template <typename S>
void ColorHead<S>::Backward(const S* params, const Inputs& in, const Outputs& out, const OutputGrads& grad,
                            S* dparams, const InputGrads& din, const DropoutPass& pass) {
  const std::size_t n = static_cast<std::size_t>(in.n), w = static_cast<std::size_t>(in_dim());
  GrowTo(draw_, 4 * n);
  ParallelRows(in.n, [&](std::size_t i) {
    const S* r = out.raw + 4 * i;
    S* d = draw_.data() + 4 * i;
    for (int c = 0; c < 3; ++c) {
      const S s = Sigmoid(r[c]);
      d[c] = grad.drgb ? grad.drgb[3 * i + c] * s * (S(1) - s) : S(0);
    }
    d[3] = grad.dlogvar ? grad.dlogvar[i] : S(0);
  });
  if (din.dgeo) GrowTo(din_, n * w);
  mlp_.Backward(params, {in.n, out.in}, {out.hidden, out.raw}, {draw_.data()}, dparams,
                {din.dgeo ? din_.data() : nullptr}, pass);
  if (!din.dgeo) return;
  ParallelRows(in.n, [&](std::size_t i) { std::copy_n(din_.data() + i * w, geo_, din.dgeo + i * geo_); });
}

template class DensityHead<float>;
template class DensityHead<double>;
template class ColorHead<float>;
template class ColorHead<double>;

}  // namespace endorecon::field
