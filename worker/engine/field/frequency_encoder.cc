#include "worker/engine/field/frequency_encoder.h"

#include <string>

#include "common/error.h"
#include "worker/engine/field/batch_loop.h"
#include "worker/engine/field/frequency_encoding.h"

namespace endorecon::field {

static_assert(TrainableModule<FrequencyEncoder<float>, float>);

template <typename S>
FrequencyEncoder<S>::FrequencyEncoder(int frequencies) : frequencies_(frequencies) {
  if (frequencies < 1 || frequencies > kMostFrequencies) {
    FailInvalid("frequency encoding: frequencies must be in [1, " + std::to_string(kMostFrequencies) +
                "], got " + std::to_string(frequencies));
  }
}

template <typename S>
int FrequencyEncoder<S>::output_dim() const {
  return FrequencyEncodingDim(frequencies_);
}

template <typename S>
void FrequencyEncoder<S>::Forward(const S*, const Inputs& in, const Outputs& out, const DropoutPass&) {
  const std::size_t d = static_cast<std::size_t>(output_dim());
  ParallelRows(in.n,
               [&](std::size_t i) { FrequencyEncode(in.pos + 3 * i, frequencies_, out.encoding + i * d); });
}

template <typename S>
void FrequencyEncoder<S>::Backward(const S*, const Inputs& in, const Outputs&, const OutputGrads& grad, S*,
                                   const InputGrads& din, const DropoutPass&) {
  if (!din.dpos) return;
  const std::size_t d = static_cast<std::size_t>(output_dim());
  ParallelRows(in.n, [&](std::size_t i) {
    FrequencyEncodeBackward(in.pos + 3 * i, frequencies_, grad.dencoding + i * d, din.dpos + 3 * i);
  });
}

template class FrequencyEncoder<float>;
template class FrequencyEncoder<double>;

}  // namespace endorecon::field
