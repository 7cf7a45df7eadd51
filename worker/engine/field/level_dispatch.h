// The one dispatch from a grid level's run-time shape (features per level, dense or hashed) to the
// compile-time shapes the per-sample loops are instantiated for, shared by the CPU grid and the CUDA
// grid kernels so both accept exactly the same shapes.
#pragma once

#include <string>
#include <type_traits>

#include "common/error.h"
#include "worker/engine/field/hash_math.h"

namespace endorecon::field {

// Calls fn(std::integral_constant<int, F>{}) for F = features.
// Throws Error(kInvalidArgument) for features other than 1, 2, 4 or 8.
template <typename Fn>
void DispatchFeatures(int features, Fn&& fn) {
  switch (features) {
    case 1:
      return fn(std::integral_constant<int, 1>{});
    case 2:
      return fn(std::integral_constant<int, 2>{});
    case 4:
      return fn(std::integral_constant<int, 4>{});
    case 8:
      return fn(std::integral_constant<int, 8>{});
    default:
      FailInvalid("hash grid features per level must be 1, 2, 4 or 8, got " + std::to_string(features));
  }
}

// Calls fn(std::integral_constant<int, F>{}, std::bool_constant<dense>{}) for F = features.
// Throws as DispatchFeatures.
template <typename Fn>
void DispatchLevel(int features, const GridLevel& level, Fn&& fn) {
  DispatchFeatures(features, [&](auto f) {
    if (level.dense) {
      fn(f, std::true_type{});
    } else {
      fn(f, std::false_type{});
    }
  });
}

}  // namespace endorecon::field
