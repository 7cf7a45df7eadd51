// Stratified sampling of [near, far]: n equal bins, one uniformly jittered sample per bin.
#pragma once

#include "common/hd.h"

namespace endorecon::render {

// Writes n ascending samples s[0..n) and their intervals delta[0..n) (conventions in
// ray_samples.h). Bin j is [e_j, e_{j+1}] with e_j = near + (far - near) j / n; its sample is
// e_j + u_j (e_{j+1} - e_j) with u_j = uniform(first_draw + j) in [0, 1), and its interval is the
// whole bin, delta_j = e_{j+1} - e_j, so the intervals tile [near, far] exactly. `uniform` is any
// callable taking a uint32 draw index (CounterRng, or fixed values in tests); a constant 0.5 gives
// bin centres. Requires near <= far and n >= 0.
template <typename S, typename Uniform>
ENDORECON_HD void StratifiedSamples(S near, S far, int n, const Uniform& uniform, S* s, S* delta,
                                    unsigned first_draw = 0) {
  const S length = far - near;
  for (int j = 0; j < n; ++j) {
    const S lo = near + length * S(j) / S(n);
    const S hi = j + 1 == n ? far : near + length * S(j + 1) / S(n);
    const S u = static_cast<S>(uniform(static_cast<unsigned>(first_draw + j)));
    s[j] = lo + u * (hi - lo);
    delta[j] = hi - lo;
  }
}

}  // namespace endorecon::render
