#include "worker/engine/field/temporal_blend.h"

#include <algorithm>
#include <cmath>

namespace endorecon::field {

static_assert(TrainableModule<TemporalBlend<float>, float>);

template <typename S>
TemporalBlend<S>::TemporalBlend(int grids, int hidden)
    : grids_(grids), mlp_(1, {hidden}, grids, 0.0, 0x7b1u) {}

template <typename S>
void TemporalBlend<S>::Init(S* params, std::uint64_t seed) const {
  mlp_.Init(params, seed, S(0));
}

template <typename S>
void TemporalBlend<S>::Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass&) {
  S* const hidden[] = {out.hidden};
  mlp_.Forward(params, {in.n, in.time}, {hidden, out.beta}, DropoutPass{});
  const int g = grids_;
  ParallelRows(in.n, [&](std::size_t s) {
    S* b = out.beta + s * g;
    const S top = *std::max_element(b, b + g);
    S sum = S(0);
    for (int i = 0; i < g; ++i) sum += (b[i] = std::exp(b[i] - top));
    for (int i = 0; i < g; ++i) b[i] /= sum;
  });
}

template <typename S>
void TemporalBlend<S>::Backward(const S* params, const Inputs& in, const Outputs& out,
                                const OutputGrads& grad, S* dparams, const InputGrads&, const DropoutPass&) {
  const int g = grids_;
  GrowTo(dlogits_, static_cast<std::size_t>(in.n) * g);
  ParallelRows(in.n, [&](std::size_t s) {
    const S* b = out.beta + s * g;
    const S* db = grad.dbeta + s * g;
    S* dl = dlogits_.data() + s * g;
    S mean = S(0);
    for (int i = 0; i < g; ++i) mean += b[i] * db[i];
    // Softmax backward: dlogit_i = beta_i (dbeta_i - sum_k beta_k dbeta_k).
    for (int i = 0; i < g; ++i) dl[i] = b[i] * (db[i] - mean);
  });
  S* const hidden[] = {out.hidden};
  mlp_.Backward(params, {in.n, in.time}, {hidden, out.beta}, {dlogits_.data()}, dparams, {}, DropoutPass{});
}

template class TemporalBlend<float>;
template class TemporalBlend<double>;

}  // namespace endorecon::field
