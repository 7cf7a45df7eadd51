// A named block of trainable parameters and its gradient, owned by the module (or field) that made it.
// The optimiser walks these; learning rates are set per block name. One type for the whole engine:
// float for training, double where the tests check gradients.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

namespace endorecon::field {

template <typename S>
struct ParamBlock {
  std::string name;
  S* value = nullptr;
  S* grad = nullptr;
  std::size_t size = 0;
};

// The values of the block named `name` among `blocks`, or null when there is none (an optional
// module, as the learned background, that this field was built without).
template <typename S>
S* BlockValues(const std::vector<ParamBlock<S>>& blocks, const std::string& name) {
  for (const auto& block : blocks) {
    if (block.name == name) return block.value;
  }
  return nullptr;
}

}  // namespace endorecon::field
