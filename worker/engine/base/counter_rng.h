// Counter-based random numbers for the whole engine, callable from CPU loops and CUDA kernels alike.
// Written by hand because no Debian library offers one that is __host__ __device__: a draw is a pure
// function of (seed, stream, index), so rays and samples can be drawn in any order, on any thread or
// device, and the same seed gives the same draws. The bottom layer of the engine: it includes nothing
// of it, and everything may include it.
#pragma once

#include <cmath>
#include <cstdint>

#include "common/hd.h"

namespace endorecon::base {

// The splitmix64 finaliser: a bijection on 64-bit words with full avalanche.
ENDORECON_HD std::uint64_t Mix64(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

// Combines two keys into one, e.g. a stream from (iteration, ray index).
ENDORECON_HD std::uint64_t HashCombine(std::uint64_t a, std::uint64_t b) { return Mix64(Mix64(a) ^ b); }

// A well-mixed seed for stream `stream` of `seed` (splitmix64 stepped `stream + 1` times), e.g. one
// seed per frame of a synthetic clip.
ENDORECON_HD std::uint64_t StreamSeed(std::uint64_t seed, std::uint64_t stream) {
  return Mix64(seed + 0x9e3779b97f4a7c15ull * stream);
}

// Maps 64 random bits to a uniform value in [0, 1): never 1, so 1 - u is never 0.
template <typename S>
ENDORECON_HD S UniformFromBits(std::uint64_t bits) {
  if constexpr (sizeof(S) == 4) {
    return static_cast<S>(bits >> 40) * static_cast<S>(0x1p-24);
  } else {
    return static_cast<S>(bits >> 11) * static_cast<S>(0x1p-53);
  }
}

// A standard normal value from two uniforms in [0, 1) (Box-Muller, cosine branch).
template <typename S>
ENDORECON_HD S NormalFromUniforms(S u1, S u2) {
  const S radius = std::sqrt(S(-2) * std::log(S(1) - u1));
  return radius * std::cos(S(6.283185307179586476925) * u2);
}

// Uniform draws in [0, 1) for one stream (typically one ray in one iteration): rng(i) is the i-th
// draw. Samplers take any callable of this shape, so tests can pass fixed values instead.
template <typename S>
struct CounterRng {
  std::uint64_t key;

  ENDORECON_HD CounterRng(std::uint64_t seed, std::uint64_t stream) : key(HashCombine(seed, stream)) {}
  ENDORECON_HD S operator()(std::uint32_t index) const { return UniformFromBits<S>(HashCombine(key, index)); }
};

}  // namespace endorecon::base
