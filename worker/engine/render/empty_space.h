// Empty-space skipping: once a coarse occupancy test (an occupancy grid, or a cheap density pass)
// says a sample lies where the density is negligible, the sample is dropped before the field is
// evaluated. A dropped sample would have had alpha ~ 0, so removing it leaves the transmittance of
// the samples behind it and every rendered value unchanged up to that negligible density; the kept
// samples keep their own intervals (so the intervals no longer tile the ray, which the renderer
// does not need). Which occupancy test to use and how often to refresh it is the trainer's choice.
#pragma once

#include <cstdint>

#include "common/hd.h"

namespace endorecon::render {

// Keeps the samples j with occupied[j] != 0, in order, at the front of s and delta; returns how
// many were kept. If source_index is not null, source_index[i] is the original index of kept
// sample i (to scatter per-sample results back).
template <typename S>
ENDORECON_HD int CompactOccupiedSamples(const uint8_t* occupied, int n, S* s, S* delta, int* source_index) {
  int kept = 0;
  for (int j = 0; j < n; ++j) {
    if (!occupied[j]) continue;
    s[kept] = s[j];
    delta[kept] = delta[j];
    if (source_index != nullptr) source_index[kept] = j;
    ++kept;
  }
  return kept;
}

}  // namespace endorecon::render
