// Seconds of wall time since a steady-clock instant: the one stopwatch the engine's phases time
// themselves with (training, evaluation, the whole run).
#pragma once

#include <chrono>

namespace endorecon::base {

inline double SecondsSince(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace endorecon::base
