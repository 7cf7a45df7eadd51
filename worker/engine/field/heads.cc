#include "worker/engine/field/heads.h"

#include <algorithm>
#include <string>

#include "common/error.h"
#include "worker/engine/field/heads_math.h"

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
  ParallelRows(in.n, [&](std::size_t i) { DensityOutputs(out.raw + i * w, out.sigma + i, out.logvar + i); });
}

template <typename S>
void DensityHead<S>::Backward(const S* params, const Inputs& in, const Outputs& out, const OutputGrads& grad,
                              S* dparams, const InputGrads& din, const DropoutPass& pass) {
  const std::size_t w = static_cast<std::size_t>(raw_dim());
  GrowTo(draw_, static_cast<std::size_t>(in.n) * w);
  ParallelRows(in.n, [&](std::size_t i) {
    DensityOutputsBackward(out.raw + i * w, grad.dsigma ? grad.dsigma + i : nullptr,
                           grad.dlogvar ? grad.dlogvar + i : nullptr,
                           grad.dgeo ? grad.dgeo + i * geo_ : nullptr, geo_, draw_.data() + i * w);
  });
  mlp_.Backward(params, {in.n, in.feat}, {out.hidden, out.raw}, {draw_.data()}, dparams, {din.dfeat}, pass);
}

template <typename S>
ColorHead<S>::ColorHead(const HeadsConfig& config)
    : geo_(config.geo_features),
      time_frequencies_(config.color_time_frequencies),
      mlp_(config.geo_features + kShDims + 2 * std::max(config.color_time_frequencies, 0),
           config.color_hidden, 4, config.ColorDropout(), kColorStream) {
  if (config.color_time_frequencies < 0 || config.color_time_frequencies > kMaxTimeFrequencies) {
    FailInvalid("colour head: color_time_frequencies must be in [0, " + std::to_string(kMaxTimeFrequencies) +
                "], got " + std::to_string(config.color_time_frequencies));
  }
}

template <typename S>
void ColorHead<S>::Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass& pass) {
  const std::size_t w = static_cast<std::size_t>(in_dim());
  ParallelRows(in.n, [&](std::size_t i) {
    ColorInput(in.geo + i * in.geo_stride, geo_, in.dir + 3 * i, time_frequencies_ ? in.time[i] : S(0),
               time_frequencies_, out.in + i * w);
  });
  mlp_.Forward(params, {in.n, out.in}, {out.hidden, out.raw}, pass);
  ParallelRows(in.n, [&](std::size_t i) { ColorOutputs(out.raw + 4 * i, out.rgb + 3 * i, out.logvar + i); });
}

template <typename S>
void ColorHead<S>::Backward(const S* params, const Inputs& in, const Outputs& out, const OutputGrads& grad,
                            S* dparams, const InputGrads& din, const DropoutPass& pass) {
  const std::size_t n = static_cast<std::size_t>(in.n), w = static_cast<std::size_t>(in_dim());
  GrowTo(draw_, 4 * n);
  ParallelRows(in.n, [&](std::size_t i) {
    ColorOutputsBackward(out.raw + 4 * i, grad.drgb ? grad.drgb + 3 * i : nullptr,
                         grad.dlogvar ? grad.dlogvar + i : nullptr, draw_.data() + 4 * i);
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
