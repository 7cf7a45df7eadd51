// Dropout masks drawn from a counter-based generator: whether unit j of sample row r is kept is a pure
// function of (key, r * width + j), so Backward (or a CUDA kernel) reproduces the mask without storing
// it, and the mask does not depend on how a batch is split into tiles or threads. Written by hand
// (two rounds of murmur3's 32-bit finaliser, keyed per round) because it must vectorise over units
// and run inside kernels; no Debian library offers that.
#pragma once

#include <cstdint>

#include "common/hd.h"

namespace endorecon::field {

ENDORECON_HD std::uint32_t Fmix32(std::uint32_t h) {
  h ^= h >> 16;
  h *= 0x85ebca6bu;
  h ^= h >> 13;
  h *= 0xc2b2ae35u;
  h ^= h >> 16;
  return h;
}

// The two round keys of one mask (one MLP layer in one forward pass).
struct DropoutKey {
  std::uint32_t k0 = 0, k1 = 0;
};

ENDORECON_HD DropoutKey MakeDropoutKey(std::uint64_t seed, std::uint32_t stream) {
  DropoutKey key;
  key.k0 = Fmix32(static_cast<std::uint32_t>(seed) ^ Fmix32(stream * 0x9e3779b9u + 1u));
  key.k1 = Fmix32(static_cast<std::uint32_t>(seed >> 32) ^ Fmix32(key.k0 + 0x7f4a7c15u));
  return key;
}

// 32 uniform bits for one element.
ENDORECON_HD std::uint32_t DropoutBits(DropoutKey key, std::uint32_t counter) {
  return Fmix32(Fmix32(counter ^ key.k0) ^ key.k1);
}

// The element is kept when its bits are at or above threshold = round(p * 2^32) (p = drop rate).
ENDORECON_HD bool DropoutKeep(DropoutKey key, std::uint32_t counter, std::uint32_t threshold) {
  return DropoutBits(key, counter) >= threshold;
}

}  // namespace endorecon::field
