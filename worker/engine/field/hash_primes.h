// The primes of instant-ngp's spatial hash (Teschner et al.): vertex (x, y, z) of a hashed grid level
// goes to slot (x * 1 ^ y * kHashPrimeY ^ z * kHashPrimeZ) mod table size. The first prime is 1 so
// that neighbouring x share cache lines. One definition for the scalar, AVX-512 and CUDA lookups.
#pragma once

#include <cstdint>

namespace endorecon::field {

inline constexpr std::uint32_t kHashPrimeY = 2654435761u;
inline constexpr std::uint32_t kHashPrimeZ = 805459861u;

}  // namespace endorecon::field
