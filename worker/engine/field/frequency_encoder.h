// The frequency encoding (frequency_encoding.h) as a module of the field (module.h) with no
// parameters: the ablation's baseline encoder in place of the grid ensemble and the temporal blend.
#pragma once

#include <cstddef>
#include <cstdint>

#include "worker/engine/field/module.h"

namespace endorecon::field {

inline constexpr int kMostFrequencies = 16;  // octaves of the encoding at most

template <typename S>
class FrequencyEncoder {
 public:
  struct Inputs {
    int n = 0;
    const S* pos = nullptr;  // n x 3
  };
  struct Outputs {
    S* encoding = nullptr;  // n x output_dim()
  };
  struct OutputGrads {
    const S* dencoding = nullptr;  // n x output_dim()
  };
  struct InputGrads {
    S* dpos = nullptr;  // n x 3
  };

  // Throws Error(kInvalidArgument) for frequencies outside [1, 16].
  explicit FrequencyEncoder(int frequencies);

  int frequencies() const { return frequencies_; }
  int output_dim() const;
  std::size_t param_count() const { return 0; }
  void Init(S*, std::uint64_t) const {}

  void Forward(const S* params, const Inputs& in, const Outputs& out, const DropoutPass& pass);
  void Backward(const S* params, const Inputs& in, const Outputs& out, const OutputGrads& grad, S* dparams,
                const InputGrads& din, const DropoutPass& pass);

 private:
  int frequencies_;
};

}  // namespace endorecon::field
