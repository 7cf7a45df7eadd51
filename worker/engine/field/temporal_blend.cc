#include "worker/engine/field/temporal_blend.h"

#include <algorithm>
#include <cmath>

namespace endorecon::field {

static_assert(TrainableModule<TemporalBlend<float>, float>);

template <typename S>
TemporalBlend<S>::TemporalBlend(int grids, int feature_dim, int hidden)
    : grids_(grids), feature_dim_(feature_dim), mlp_(1, {hidden}, grids, 0.0, 0x7b1u) {}

template <typename S>
void TemporalBlend<S>::Init(S* params, std::uint64_t seed) const {
  mlp_.Init(params, seed, S(0));
}

template <typename S>
void TemporalBlend<S>::Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass&) {
  S* const hidden[] = {out.hidden};
  mlp_.Forward(params, {in.n, in.time}, {hidden, out.beta}, DropoutPass{});
  const int g = grids_, d = feature_dim_;
  ParallelRows(in.n, [&](std::size_t s) {
    S* b = out.beta + s * g;
    const S top = *std::max_element(b, b + g);
    S sum = S(0);
    for (int i = 0; i < g; ++i) sum += (b[i] = std::exp(b[i] - top));
    for (int i = 0; i < g; ++i) b[i] /= sum;
    const S* feats = in.feats + s * g * d;
    S* f = out.f + s * d;
    for (int j = 0; j < d; ++j) f[j] = b[0] * feats[j];
    for (int i = 1; i < g; ++i) {
      for (int j = 0; j < d; ++j) f[j] += b[i] * feats[i * d + j];
    }
  });
}

template <typename S>
void TemporalBlend<S>::Backward(const S* params, const Inputs& in, const Outputs& out,
                                const OutputGrads& grad, S* dparams, const InputGrads& din,
                                const DropoutPass&) {
  const int g = grids_, d = feature_dim_;
  GrowTo(dlogits_, static_cast<std::size_t>(in.n) * g);
  ParallelRows(in.n, [&](std::size_t s) {
    const S* b = out.beta + s * g;
    const S* feats = in.feats + s * g * d;
    const S* df = grad.df + s * d;
    S* dl = dlogits_.data() + s * g;
    S mean = S(0);
    for (int i = 0; i < g; ++i) {
      S dot = S(0);
      for (int j = 0; j < d; ++j) dot += df[j] * feats[i * d + j];
      dl[i] = dot;
      mean += b[i] * dot;
    }
    // Softmax backward: dlogit_i = beta_i (dbeta_i - sum_k beta_k dbeta_k).
    for (int i = 0; i < g; ++i) dl[i] = b[i] * (dl[i] - mean);
    if (din.dfeats) {
      S* dfeats = din.dfeats + s * g * d;
      for (int i = 0; i < g; ++i) {
        for (int j = 0; j < d; ++j) dfeats[i * d + j] = b[i] * df[j];
      }
    }
  });
  S* const hidden[] = {out.hidden};
  mlp_.Backward(params, {in.n, in.time}, {hidden, out.beta}, {dlogits_.data()}, dparams, {}, DropoutPass{});
}

template class TemporalBlend<float>;
template class TemporalBlend<double>;

}  // namespace endorecon::field
