// Random numbers that are the same with every standard library for a seed: std::mt19937_64's
// output is specified by the standard, but std's distributions are not (they differ between
// libstdc++ and libc++, and between versions), so uniform and normal draws are written here.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

namespace endorecon::scene {

class PortableRandom {
 public:
  explicit PortableRandom(std::uint64_t seed) : engine_(seed) {}

  // Uniform in [0, 1), 53 random bits.
  double Uniform() { return static_cast<double>(engine_() >> 11) * 0x1.0p-53; }
  double Uniform(double lo, double hi) { return lo + (hi - lo) * Uniform(); }
  // Standard normal (Box-Muller; one of the pair is discarded to keep draws stateless).
  double Normal() {
    const double u = 1.0 - Uniform();  // (0, 1]
    return std::sqrt(-2.0 * std::log(u)) * std::cos(2.0 * std::numbers::pi * Uniform());
  }

 private:
  std::mt19937_64 engine_;
};

// A well-mixed seed for stream `stream` of `seed` (SplitMix64's finaliser), e.g. one stream per frame.
inline std::uint64_t StreamSeed(std::uint64_t seed, std::uint64_t stream) {
  std::uint64_t z = seed + 0x9e3779b97f4a7c15ULL * (stream + 1);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

}  // namespace endorecon::scene
