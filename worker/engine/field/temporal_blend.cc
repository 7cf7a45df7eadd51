#include "worker/engine/field/temporal_blend.h"

#include "worker/engine/field/blend_math.h"

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
  ParallelRows(in.n, [&](std::size_t s) { SoftmaxInPlace(out.beta + s * g, g); });
}

template <typename S>
void TemporalBlend<S>::Backward(const S* params, const Inputs& in, const Outputs& out,
                                const OutputGrads& grad, S* dparams, const InputGrads&, const DropoutPass&) {
  const int g = grids_;
  GrowTo(dlogits_, static_cast<std::size_t>(in.n) * g);
  ParallelRows(in.n, [&](std::size_t s) {
    SoftmaxBackward(out.beta + s * g, grad.dbeta + s * g, g, dlogits_.data() + s * g);
  });
  S* const hidden[] = {out.hidden};
  mlp_.Backward(params, {in.n, in.time}, {hidden, out.beta}, {dlogits_.data()}, dparams, {}, DropoutPass{});
}

template class TemporalBlend<float>;
template class TemporalBlend<double>;

}  // namespace endorecon::field
