// Per-row math of the two heads' inputs and outputs (heads.h), written once for the CPU modules and
// the CUDA kernels: the colour head's input [geo, SH(dir)], and each head's output activations and
// their gradients.
#pragma once

#include "common/hd.h"
#include "worker/engine/field/activations.h"
#include "worker/engine/field/sh_encoding.h"

namespace endorecon::field {

// raw: 2 + geo values -> sigma = TruncExp(raw0), logvar = raw1.
template <typename S>
ENDORECON_HD void DensityOutputs(const S* raw, S* sigma, S* logvar) {
  *sigma = TruncExp(raw[0]);
  *logvar = raw[1];
}

// draw (2 + geo values) from dL/dsigma, dL/dlogvar and dL/dgeo (each may be null: zero).
template <typename S>
ENDORECON_HD void DensityOutputsBackward(const S* raw, const S* dsigma, const S* dlogvar, const S* dgeo,
                                         int geo, S* draw) {
  draw[0] = dsigma ? *dsigma * TruncExpGrad(raw[0]) : S(0);
  draw[1] = dlogvar ? *dlogvar : S(0);
  for (int j = 0; j < geo; ++j) draw[2 + j] = dgeo ? dgeo[j] : S(0);
}

// The colour head's input row: geo values, then the 16 SH values of the unit direction.
template <typename S>
ENDORECON_HD void ColorInput(const S* geo, int geo_count, const S* dir, S* row) {
  for (int j = 0; j < geo_count; ++j) row[j] = geo[j];
  ShEncode(dir, row + geo_count);
}

// raw: 4 values -> rgb = sigmoid(raw0..2), logvar = raw3.
template <typename S>
ENDORECON_HD void ColorOutputs(const S* raw, S* rgb, S* logvar) {
  for (int c = 0; c < 3; ++c) rgb[c] = Sigmoid(raw[c]);
  *logvar = raw[3];
}

// draw (4 values) from dL/drgb (3) and dL/dlogvar (each may be null: zero).
template <typename S>
ENDORECON_HD void ColorOutputsBackward(const S* raw, const S* drgb, const S* dlogvar, S* draw) {
  for (int c = 0; c < 3; ++c) {
    const S s = Sigmoid(raw[c]);
    draw[c] = drgb ? drgb[c] * s * (S(1) - s) : S(0);
  }
  draw[3] = dlogvar ? *dlogvar : S(0);
}

}  // namespace endorecon::field
