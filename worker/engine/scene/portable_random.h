// Random numbers that are the same with every standard library for a seed: std::mt19937_64's
// output is specified by the standard, but std's distributions are not (they differ between
// libstdc++ and libc++, and between versions), so uniform and normal draws are written here.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <random>

#include "worker/engine/base/counter_rng.h"

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

// One seed per stream of a seed (e.g. per frame): the engine's one splitmix64 (base/counter_rng.h).
using base::StreamSeed;

}  // namespace endorecon::scene
