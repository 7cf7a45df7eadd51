// A named block of trainable parameters and its gradient buffer, owned by the module that made it.
// The optimiser walks these; learning rates are set per group name.
#pragma once

#include <cstddef>
#include <string>

namespace endorecon::train {

struct ParamGroup {
  std::string name;
  float* value = nullptr;
  float* grad = nullptr;
  std::size_t size = 0;
};

}  // namespace endorecon::train
