// Per-sample math of the hash grids, shared by the CPU loops and the CUDA kernels: grid cell lookup
// (instant-ngp's spatial hash or dense indexing), trilinear weights and their gradient.
// Every function is a pure function of its arguments: no heap, no exceptions, no STL containers.
#pragma once

#include <cmath>
#include <cstddef>
#include <cstdint>

#include "common/hd.h"
#include "worker/engine/field/hash_primes.h"

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

// instant-ngp's spatial hash (hash_primes.h), before wrapping to the table size.
ENDORECON_HD std::uint32_t SpatialHash(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  return x ^ (y * kHashPrimeY) ^ (z * kHashPrimeZ);
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
    const std::uint32_t hy[2] = {c[1] * kHashPrimeY, (c[1] + 1) * kHashPrimeY};
    const std::uint32_t hz[2] = {c[2] * kHashPrimeZ, (c[2] + 1) * kHashPrimeZ};
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

// One sample's features at one level: out[f] for f < F, the trilinear blend of its cell's corners in
// the level's table. The forward loop of the CPU grid and of the CUDA level kernel.
template <int F, bool kDense, typename S>
ENDORECON_HD ENDORECON_FIELD_INLINE void GatherLevel(const GridLevel& level, const S* table, const S* pos,
                                                     S* out) {
  std::uint32_t slot[8];
  S w[8], frac[3];
  CellCornersOf<kDense>(level, pos, slot, w, frac);
  BlendCorners<F>(table, slot, w, out);
}

// The accumulation of a scatter where one thread owns the table it adds to (the CPU's level tasks).
struct PlainAdd {
  template <typename S>
  ENDORECON_HD void operator()(S* target, S value) const {
    *target += value;
  }
};

// One sample's gradient at one level: grads[corner slot * F + f] += weight * scale * dfeat[f] for the
// 8 corners of its cell, through add(pointer, value) (PlainAdd on the CPU, an atomic add in CUDA
// kernels). With kPosition also adds the level's part of dL/dpos to dpos[0..3): the corner values it
// needs are in the cache lines the scatter touches anyway (table: the level's parameters).
template <int F, bool kDense, bool kPosition, typename S, typename Add>
ENDORECON_HD ENDORECON_FIELD_INLINE void ScatterLevel(const GridLevel& level, const S* pos, const S* dfeat,
                                                      S scale, S* grads, const S* table, S* dpos,
                                                      const Add& add) {
  std::uint32_t slot[8];
  S w[8], frac[3];
  CellCornersOf<kDense>(level, pos, slot, w, frac);
  S g[F];
  for (int f = 0; f < F; ++f) g[f] = scale * dfeat[f];
  S dot[8];
  for (int k = 0; k < 8; ++k) {
    S* gv = grads + static_cast<std::size_t>(slot[k]) * F;
    if constexpr (kPosition) {
      const S* v = table + static_cast<std::size_t>(slot[k]) * F;
      dot[k] = S(0);
      for (int f = 0; f < F; ++f) dot[k] += v[f] * g[f];
    }
    for (int f = 0; f < F; ++f) add(gv + f, w[k] * g[f]);
  }
  if constexpr (kPosition) {
    S gradient[3];
    TrilinearGradient(dot, frac, gradient);
    const S res = static_cast<S>(level.res);
    for (int a = 0; a < 3; ++a) {
      if (InsideUnit(pos[a])) dpos[a] += res * gradient[a];
    }
  }
}

}  // namespace endorecon::field
