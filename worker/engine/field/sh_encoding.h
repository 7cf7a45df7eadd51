// Real spherical harmonics of a unit view direction up to band 3 ("degree 4" in tiny-cuda-nn's
// naming): 16 values, the colour head's view encoding. No trainable parameters; the field never needs
// a derivative with respect to the direction (directions are data). Written by hand: no Debian
// library evaluates SH in a form a CUDA kernel can call.
#pragma once

#include "common/hd.h"

namespace endorecon::field {

inline constexpr int kShDims = 16;

// out[0..15] = Y_lm(d) for l = 0..3, m = -l..l, with the usual real-SH normalisation.
template <typename S>
ENDORECON_HD void ShEncode(const S* d, S* out) {
  const S x = d[0], y = d[1], z = d[2];
  const S xx = x * x, yy = y * y, zz = z * z;
  out[0] = S(0.28209479177387814);
  out[1] = S(-0.48860251190291987) * y;
  out[2] = S(0.48860251190291987) * z;
  out[3] = S(-0.48860251190291987) * x;
  out[4] = S(1.0925484305920792) * x * y;
  out[5] = S(-1.0925484305920792) * y * z;
  out[6] = S(0.94617469575755997) * zz - S(0.31539156525251999);
  out[7] = S(-1.0925484305920792) * x * z;
  out[8] = S(0.54627421529603959) * (xx - yy);
  out[9] = S(0.59004358992664352) * y * (S(-3) * xx + yy);
  out[10] = S(2.8906114426405538) * x * y * z;
  out[11] = S(0.45704579946446572) * y * (S(1) - S(5) * zz);
  out[12] = S(0.3731763325901154) * z * (S(5) * zz - S(3));
  out[13] = S(0.45704579946446572) * x * (S(1) - S(5) * zz);
  out[14] = S(1.4453057213202769) * z * (xx - yy);
  out[15] = S(0.59004358992664352) * x * (-xx + S(3) * yy);
}

// Encodes n directions (n x 3) into rows of `out` (row i starts at out + i * stride).
template <typename S>
void ShEncodeBatch(const S* dir, int n, S* out, int stride) {
  for (int i = 0; i < n; ++i) ShEncode(dir + 3 * i, out + static_cast<long>(i) * stride);
}

}  // namespace endorecon::field
