// NeRF's positional (frequency) encoding of a point, the encoder of EndoNeRF's canonical MLP and of
// the ablation's baseline row (a): per point x (3 coordinates),
//   [x, sin(2^0 pi x), cos(2^0 pi x), ..., sin(2^(L-1) pi x), cos(2^(L-1) pi x)],
// each sin/cos block over the three coordinates, 3 (1 + 2L) values in all. No trainable parameters;
// Backward gives dL/dx (the deformation needs it). Per-point math as ENDORECON_HD functions, so a
// CUDA kernel can call it; written by hand because it is a few lines no library here offers.
#pragma once

#include <cmath>

#include "common/hd.h"

namespace endorecon::field {

ENDORECON_HD int FrequencyEncodingDim(int frequencies) { return 3 * (1 + 2 * frequencies); }

template <typename S>
ENDORECON_HD void FrequencyEncode(const S* x, int frequencies, S* out) {
  out[0] = x[0];
  out[1] = x[1];
  out[2] = x[2];
  S scale = S(3.14159265358979323846);
  for (int k = 0; k < frequencies; ++k, scale *= S(2)) {
    S* block = out + 3 + 6 * k;
    for (int c = 0; c < 3; ++c) {
      block[c] = std::sin(scale * x[c]);
      block[3 + c] = std::cos(scale * x[c]);
    }
  }
}

// dx[0..3) = d(out) . d(out)/dx, overwriting dx.
template <typename S>
ENDORECON_HD void FrequencyEncodeBackward(const S* x, int frequencies, const S* dout, S* dx) {
  dx[0] = dout[0];
  dx[1] = dout[1];
  dx[2] = dout[2];
  S scale = S(3.14159265358979323846);
  for (int k = 0; k < frequencies; ++k, scale *= S(2)) {
    const S* block = dout + 3 + 6 * k;
    for (int c = 0; c < 3; ++c) {
      dx[c] += scale * (block[c] * std::cos(scale * x[c]) - block[3 + c] * std::sin(scale * x[c]));
    }
  }
}

}  // namespace endorecon::field
