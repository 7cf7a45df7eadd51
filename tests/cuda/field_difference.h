// How far two fields' parameters are apart, for the GPU tests that compare a GPU run with the CPU's.
#pragma once

#include <cmath>

#include "worker/engine/field/field.h"

namespace endorecon::cuda {

// The largest difference of a parameter block's values, relative to that block's largest magnitude
// (at least 1e-3), over all blocks.
inline double MaxRelative(const field::Field& a, const field::Field& b) {
  double worst = 0;
  const auto ab = a.Blocks();
  const auto bb = b.Blocks();
  for (std::size_t k = 0; k < ab.size(); ++k) {
    double diff = 0, scale = 1e-3;
    for (std::size_t i = 0; i < ab[k].size; ++i) {
      diff = std::fmax(diff, std::fabs(double(ab[k].value[i]) - bb[k].value[i]));
      scale = std::fmax(scale, std::fabs(double(bb[k].value[i])));
    }
    worst = std::fmax(worst, diff / scale);
  }
  return worst;
}

}  // namespace endorecon::cuda
