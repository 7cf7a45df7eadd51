// Per-sample math of the field, shared by the CPU loops and (later) CUDA kernels: grid cell lookup
// (instant-ngp's spatial hash or dense indexing), trilinear weights, and the scalar activations.
// Every function is a pure function of its arguments: no heap, no exceptions, no STL containers.
#pragma once

#include <cmath>
#include <cstdint>

#include "common/hd.h"

namespace endorecon::field {

// One level of a grid as the per-sample code sees it. A level has `res` cells per axis and so
// (res + 1)^3 vertices; it is dense (vertex index = x + y (res+1) + z (res+1)^2) when they all fit
// its table, and hashed into `entries` (a power of two) slots otherwise.
struct GridLevel {
  std::uint32_t res = 1;
  std::uint32_t dense = 1;
  std::uint32_t entries = 8;   // table slots of this level
  std::uint64_t offset = 0;    // first slot of this level in the grid's table (in slots, not scalars)
};

// instant-ngp's spatial hash: XOR of coordinates times large primes (the first prime is 1 so that
// neighbouring x share cache lines), wrapped to the table size.
ENDORECON_HD std::uint32_t SpatialHash(std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  return x ^ (y * 2654435761u) ^ (z * 805459861u);
}

// A coordinate in [0, 1]: values outside are clamped, NaN and -Inf map to 0 and +Inf to 1, so a bad
// input always reads a valid cell. The derivative of this map is 1 strictly inside (0, 1), else 0.
template <typename S>
ENDORECON_HD S ClampUnit(S x) {
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
ENDORECON_HD std::uint32_t CellOf(S u, std::uint32_t res, S* frac) {
  const S p = u * static_cast<S>(res);
  std::uint32_t c = static_cast<std::uint32_t>(p);
  if (c >= res) c = res - 1;
  *frac = p - static_cast<S>(c);
  return c;
}

// Slot of vertex (x, y, z) of a level.
ENDORECON_HD std::uint32_t VertexSlot(const GridLevel& level, std::uint32_t x, std::uint32_t y, std::uint32_t z) {
  if (level.dense) {
    const std::uint32_t side = level.res + 1;
    return x + side * (y + side * z);
  }
  return SpatialHash(x, y, z) & (level.entries - 1);
}

// The 8 corners of the cell around `pos` (3 values, clamped to [0, 1] here): their slots (relative to
// the level's offset) and trilinear weights, corner k having offsets (k & 1, k >> 1 & 1, k >> 2 & 1).
// `frac` receives the fractional position (for derivatives).
template <typename S>
ENDORECON_HD void CellCorners(const GridLevel& level, const S* pos, std::uint32_t* slot, S* weight, S* frac) {
  std::uint32_t c[3];
  for (int a = 0; a < 3; ++a) c[a] = CellOf(ClampUnit(pos[a]), level.res, &frac[a]);
  for (int k = 0; k < 8; ++k) {
    const std::uint32_t dx = k & 1, dy = (k >> 1) & 1, dz = (k >> 2) & 1;
    slot[k] = VertexSlot(level, c[0] + dx, c[1] + dy, c[2] + dz);
    weight[k] = (dx ? frac[0] : S(1) - frac[0]) * (dy ? frac[1] : S(1) - frac[1]) * (dz ? frac[2] : S(1) - frac[2]);
  }
}

// d weight[k] / d frac[axis] for the trilinear weights of CellCorners.
template <typename S>
ENDORECON_HD S CornerWeightDerivative(int k, int axis, const S* frac) {
  S d = S(1);
  for (int a = 0; a < 3; ++a) {
    const bool high = (k >> a) & 1;
    if (a == axis) {
      d *= high ? S(1) : S(-1);
    } else {
      d *= high ? frac[a] : S(1) - frac[a];
    }
  }
  return d;
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
