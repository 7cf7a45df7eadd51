// Per-sample math of the field, shared by the CPU loops and (later) CUDA kernels: grid cell lookup
// (instant-ngp's spatial hash or dense indexing), trilinear weights, and the scalar activations.
// Every function is a pure function of its arguments: no heap, no exceptions, no STL containers.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "common/hd.h"

// The lookups below sit in the innermost per-sample loops: inlining them lets the compiler keep the 8
// slots and weights in registers (GCC otherwise keeps the larger ones out of line). The attribute
// alone, also under nvcc: ENDORECON_HD already says inline, and __forceinline__ would say it again.
#if defined(__GNUC__) || defined(__CUDACC__)
#define ENDORECON_FIELD_INLINE __attribute__((always_inline))
#else
#define ENDORECON_FIELD_INLINE
#endif

namespace endorecon::field {

// One level of a grid as the per-sample code sees it. A level has `res` cells per axis and so
// (res + 1)^3 vertices; it is dense (vertex index = x + y (res+1) + z (res+1)^2) when they all fit
// its table, and hashed into `entries` (a power of two) slots otherwise.
struct GridLevel {
  std::uint32_t res = 1;
  std::uint32_t dense = 1;
  std::uint32_t entries = 8;  // table slots of this level
  std::uint64_t offset = 0;   // first slot of this level in the grid's table (in slots, not scalars)
};

// instant-ngp's spatial hash: XOR of coordinates times large primes (the first prime is 1 so that
// neighbouring x share cache lines), wrapped to the table size.
ENDORECON_HD std::uint32_t SpatialHash(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  return x ^ (y * 2654435761u) ^ (z * 805459861u);
}

// A coordinate in [0, 1]: values outside are clamped, NaN and -Inf map to 0 and +Inf to 1, so a bad
// input always reads a valid cell. The derivative of this map is 1 strictly inside (0, 1), else 0.
template <typename S>
ENDORECON_HD ENDORECON_FIELD_INLINE S ClampUnit(S x) {
  if (!(x > S(0))) return S(0);
  return x < S(1) ? x : S(1);
}

template <typename S>
ENDORECON_HD bool InsideUnit(S x) {
  return x > S(0) && x < S(1);
}

// The cell containing `u` (in [0, 1], already clamped) at `res` cells per axis, and the fractional
// position inside it (in [0, 1]). u = 1 falls in the last cell with fraction 1.
template <typename S>
ENDORECON_HD ENDORECON_FIELD_INLINE std::uint32_t CellOf(S u, std::uint32_t res, S* frac) {
  const S p = u * static_cast<S>(res);
  std::uint32_t c = static_cast<std::uint32_t>(p);
  if (c >= res) c = res - 1;
  *frac = p - static_cast<S>(c);
  return c;
}

// Slot of vertex (x, y, z) of a level.
ENDORECON_HD std::uint32_t VertexSlot(const GridLevel& level, std::uint32_t x, std::uint32_t y,
                                      std::uint32_t z) {
  if (level.dense) {
    const std::uint32_t side = level.res + 1;
    return x + side * (y + side * z);
  }
  return SpatialHash(x, y, z) & (level.entries - 1);
}

// The 8 corners of the cell around `pos` (3 values, clamped to [0, 1] here): their slots (relative to
// the level's offset) and trilinear weights, corner k having offsets (k & 1, k >> 1 & 1, k >> 2 & 1).
// `frac` receives the fractional position (for derivatives). kDense must equal level.dense: the
// branch is a template argument so the per-sample loops of one level carry none.
template <bool kDense, typename S>
ENDORECON_HD ENDORECON_FIELD_INLINE void CellCornersOf(const GridLevel& level, const S* pos,
                                                       std::uint32_t* slot, S* weight, S* frac) {
  std::uint32_t c[3];
  for (int a = 0; a < 3; ++a) c[a] = CellOf(ClampUnit(pos[a]), level.res, &frac[a]);
  if constexpr (kDense) {
    const std::uint32_t side = level.res + 1, plane = side * side;
    const std::uint32_t base = c[0] + side * c[1] + plane * c[2];
    for (int k = 0; k < 8; ++k) slot[k] = base + (k & 1) + ((k >> 1) & 1) * side + ((k >> 2) & 1) * plane;
  } else {
    const std::uint32_t mask = level.entries - 1;
    const std::uint32_t hy[2] = {c[1] * 2654435761u, (c[1] + 1) * 2654435761u};
    const std::uint32_t hz[2] = {c[2] * 805459861u, (c[2] + 1) * 805459861u};
    for (int k = 0; k < 8; ++k) slot[k] = ((c[0] + (k & 1)) ^ hy[(k >> 1) & 1] ^ hz[(k >> 2) & 1]) & mask;
  }
  const S wx[2] = {S(1) - frac[0], frac[0]}, wy[2] = {S(1) - frac[1], frac[1]},
          wz[2] = {S(1) - frac[2], frac[2]};
  for (int k = 0; k < 8; ++k) weight[k] = wx[k & 1] * wy[(k >> 1) & 1] * wz[(k >> 2) & 1];
}

template <typename S>
ENDORECON_HD ENDORECON_FIELD_INLINE void CellCorners(const GridLevel& level, const S* pos,
                                                     std::uint32_t* slot, S* weight, S* frac) {
  if (level.dense) {
    CellCornersOf<true>(level, pos, slot, weight, frac);
  } else {
    CellCornersOf<false>(level, pos, slot, weight, frac);
  }
}

// out[f] = sum_k weight[k] * table[slot[k] * F + f] for f < F: a cell's 8 corner features blended
// with the weights of CellCorners (accumulated in registers, stored once).
template <int F, typename S>
ENDORECON_HD ENDORECON_FIELD_INLINE void BlendCorners(const S* table, const std::uint32_t* slot,
                                                      const S* weight, S* out) {
  S acc[F] = {};
  for (int k = 0; k < 8; ++k) {
    const S* v = table + static_cast<std::size_t>(slot[k]) * F;
    for (int f = 0; f < F; ++f) acc[f] += weight[k] * v[f];
  }
  for (int f = 0; f < F; ++f) out[f] = acc[f];
}

// Gradient of sum_k weight[k] * value[k] with respect to the fractional position, given value[k]
// for the 8 corners of CellCorners (multiply by the resolution for d/dpos).
template <typename S>
ENDORECON_HD ENDORECON_FIELD_INLINE void TrilinearGradient(const S* value, const S* frac, S* grad) {
  const S wx[2] = {S(1) - frac[0], frac[0]}, wy[2] = {S(1) - frac[1], frac[1]},
          wz[2] = {S(1) - frac[2], frac[2]};
  grad[0] = grad[1] = grad[2] = S(0);
  for (int k = 0; k < 8; k += 2) grad[0] += wy[(k >> 1) & 1] * wz[k >> 2] * (value[k + 1] - value[k]);
  for (int j = 0; j < 4; ++j) {
    const int k = (j & 1) | ((j >> 1) << 2);  // corners with y = 0: 0, 1, 4, 5
    grad[1] += wx[k & 1] * wz[k >> 2] * (value[k + 2] - value[k]);
  }
  for (int k = 0; k < 4; ++k) grad[2] += wx[k & 1] * wy[k >> 1] * (value[k + 4] - value[k]);
}

// Density activation: exp(min(x, 15)). The cap keeps a runaway raw value from overflowing float
// (e^15 ~ 3.3e6 is far beyond any useful density). TruncExpGrad is exp(min(x, 15)) too, also above
// the cap (as instant-ngp's trunc_exp): a density stuck above the cap still gets a gradient back down.
template <typename S>
ENDORECON_HD S TruncExp(S x) {
  return std::exp(x < S(15) ? x : S(15));
}

template <typename S>
ENDORECON_HD S TruncExpGrad(S x) {
  return TruncExp(x);
}

// Logistic sigmoid, never overflowing (exp of a non-positive argument only).
template <typename S>
ENDORECON_HD S Sigmoid(S x) {
  if (x >= S(0)) return S(1) / (S(1) + std::exp(-x));
  const S e = std::exp(x);
  return e / (S(1) + e);
}

// log(1 + e^x) without overflow for large x or loss of precision for very negative x.
template <typename S>
ENDORECON_HD S Softplus(S x) {
  return (x > S(0) ? x : S(0)) + std::log1p(std::exp(-std::fabs(x)));
}

}  // namespace endorecon::field
