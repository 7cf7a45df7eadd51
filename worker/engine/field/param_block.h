// A named block of trainable parameters and its gradient, owned by the module (or field) that made it.
// The optimiser walks these; learning rates are set per block name. One type for the whole engine:
// float for training, double where the tests check gradients.
#pragma once

#include <cstddef>
#include <string>

namespace endorecon::field {

template <typename S>
struct ParamBlock {
  std::string name;
  S* value = nullptr;
  S* grad = nullptr;
  std::size_t size = 0;
};

}  // namespace endorecon::field
