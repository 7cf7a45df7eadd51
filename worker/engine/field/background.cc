#include "worker/engine/field/background.h"

#include <algorithm>

#include "worker/engine/field/background_math.h"
#include "worker/engine/field/hash_math.h"

namespace endorecon::field {

static_assert(TrainableModule<Background<float>, float>);

template <typename S>
std::size_t Background<S>::param_count() const {
  return kBackgroundParams;
}

template <typename S>
void Background<S>::Init(S* params, std::uint64_t) const {
  std::fill_n(params, param_count(), S(0));
}

template <typename S>
void Background<S>::Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass&) {
  ParallelRows(in.n, [&](std::size_t i) { BackgroundSample(params, in.dir + 3 * i, out.rgb + 3 * i); });
}

template <typename S>
void Background<S>::Backward(const S*, const Inputs& in, const Outputs& out, const OutputGrads& grad,
                             S* dparams, const InputGrads&, const DropoutPass&) {
  if (!grad.drgb) return;
  // Every ray adds to all 48 parameters: a partial block per task, added in task order.
  partials_.Reset(TaskCount(in.n, kTaskRows), param_count());
  ParallelTasks(in.n, kTaskRows, [&](int task, int row0, int rows) {
    S* partial = partials_.task(task);
    for (std::size_t i = static_cast<std::size_t>(row0); i < static_cast<std::size_t>(row0 + rows); ++i)
      BackgroundSampleBackward(in.dir + 3 * i, out.rgb + 3 * i, grad.drgb + 3 * i, partial, PlainAdd{});
  });
  partials_.AddTo(dparams);
}

template class Background<float>;
template class Background<double>;

}  // namespace endorecon::field
