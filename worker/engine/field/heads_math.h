// Per-row math of the two heads' inputs and outputs (heads.h), written once for the CPU modules and
// the CUDA kernels: the colour head's input [geo, SH(dir), time features], and each head's output
// activations and their gradients.
#pragma once

#include <cmath>

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

// The colour head's input row: geo values, the 16 SH values of the unit direction, then for
// k = 0 .. time_frequencies - 1 the pair sin(2^k pi t), cos(2^k pi t) of the sample's time (t read as
// given; the lowest pair already tells every t in [0, 1] apart). The time features let the tissue's
// appearance change with time apart from its motion: speculars that follow a moving light, tissue
// that reddens or blanches.
template <typename S>
ENDORECON_HD void ColorInput(const S* geo, int geo_count, const S* dir, S t, int time_frequencies, S* row) {
  for (int j = 0; j < geo_count; ++j) row[j] = geo[j];
  ShEncode(dir, row + geo_count);
  if (time_frequencies <= 0) return;
  // One sin/cos pair, then the double-angle formulas for the higher frequencies (each step at most
  // doubles the rounding error: a few ulp at kMaxTimeFrequencies, far below what the head resolves).
  S* time_row = row + geo_count + kShDims;
  const S angle = S(3.14159265358979323846) * t;
  S sine = std::sin(angle), cosine = std::cos(angle);
  for (int k = 0; k < time_frequencies; ++k) {
    time_row[2 * k] = sine;
    time_row[2 * k + 1] = cosine;
    const S doubled = S(2) * sine * cosine;
    cosine = (cosine - sine) * (cosine + sine);
    sine = doubled;
  }
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
