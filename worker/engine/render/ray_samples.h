// The conventions every sampler follows, and the small helpers they share.
//
// A ray's samples are two arrays of n values: positions s[j] (the ray parameter, which is z-depth,
// see scene/camera.h), ascending, and interval lengths delta[j] >= 0. Sample j stands for the
// interval of length delta[j] that contains s[j]; the intervals are contiguous and do not overlap,
// so sum(delta) is the length of ray the samples cover and every interval is finite (there is no
// "1e10 last interval"). The density and colour at s[j] are taken as constant over its interval.
#pragma once

#include "common/hd.h"

namespace endorecon::render {

// Sorts v[0..n) ascending in place. Insertion sort: no heap and no recursion (CUDA-friendly), and
// fast for the few dozen samples of one ray, which usually arrive nearly sorted.
template <typename S>
ENDORECON_HD void SortAscending(S* v, int n) {
  for (int i = 1; i < n; ++i) {
    const S x = v[i];
    int j = i - 1;
    while (j >= 0 && v[j] > x) {
      v[j + 1] = v[j];
      --j;
    }
    v[j + 1] = x;
  }
}

// Intervals around ascending samples s[0..n): inner edges at the midpoints between neighbours,
// outer edges half a neighbour spacing beyond the first and last sample (mirrored), clipped to
// [lo, hi]. A single sample gets [lo, hi]. Writes delta[0..n).
template <typename S>
ENDORECON_HD void MidpointIntervals(const S* s, int n, S lo, S hi, S* delta) {
  if (n <= 0) return;
  if (n == 1) {
    delta[0] = hi - lo;
    return;
  }
  S left = s[0] - S(0.5) * (s[1] - s[0]);
  left = left < lo ? lo : left;
  for (int j = 0; j < n; ++j) {
    S right = j + 1 < n ? S(0.5) * (s[j] + s[j + 1]) : s[j] + S(0.5) * (s[j] - s[j - 1]);
    right = right > hi ? hi : right;
    delta[j] = right > left ? right - left : S(0);
    left = right > left ? right : left;
  }
}

}  // namespace endorecon::render
