// AVX-512 kernels of one grid level for float tables with 2 features per level (the CPU preset): the
// same math as GatherLevel / ScatterLevel (hash_math.h), 16 samples at a time.
// The cell, slot and weight arithmetic runs across samples in vectors and the forward reads use
// 64-bit gathers (one slot = 2 floats); the table scatter stays scalar (slots of a block may repeat).
// Only hash_grid.cc includes this; other shapes, double and non-AVX-512 builds use the portable
// kernels, which the tests compare these against.
#pragma once

#include <cstdint>

#include "worker/engine/field/hash_math.h"

#if defined(__AVX512F__) && defined(__AVX512DQ__)
// GCC 12 reports a false "maybe uninitialized" inside its own AVX-512 intrinsics (_mm512_undefined);
// the warning is located in those headers, so it is silenced for the including file.
#if !defined(__clang__)  // clang has no such warning, and refuses to ignore an unknown one
#pragma GCC diagnostic ignored "-Wmaybe-uninitialized"
#endif
#include <immintrin.h>
#define ENDORECON_FIELD_AVX512 1

namespace endorecon::field::simd {

inline constexpr int kBlock = 16;

// The 8 corners of 16 samples' cells.
struct Corners {
  __m512i slot[8];
  __m512 weight[8];
  __m512 frac[3];
  __mmask16 inside[3];  // coordinate strictly inside (0, 1): the gradient passes
};

// x, y, z of 16 consecutive samples of an n x 3 array.
inline void LoadPositions(const float* pos, __m512* xyz) {
  const __m512 a = _mm512_loadu_ps(pos), b = _mm512_loadu_ps(pos + 16), c = _mm512_loadu_ps(pos + 32);
  const __m512i ab[3] = {_mm512_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21, 24, 27, 30, 0, 0, 0, 0, 0),
                         _mm512_setr_epi32(1, 4, 7, 10, 13, 16, 19, 22, 25, 28, 31, 0, 0, 0, 0, 0),
                         _mm512_setr_epi32(2, 5, 8, 11, 14, 17, 20, 23, 26, 29, 0, 0, 0, 0, 0, 0)};
  const __m512i from_c[3] = {_mm512_setr_epi32(0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 4, 7, 10, 13),
                             _mm512_setr_epi32(0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 2, 5, 8, 11, 14),
                             _mm512_setr_epi32(0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 3, 6, 9, 12, 15)};
  const __mmask16 c_lanes[3] = {0xF800, 0xF800, 0xFC00};  // lanes filled from c (z: lane 10 is c[0])
  for (int axis = 0; axis < 3; ++axis) {
    xyz[axis] =
        _mm512_mask_permutexvar_ps(_mm512_permutex2var_ps(a, ab[axis], b), c_lanes[axis], from_c[axis], c);
  }
}

template <bool kDense>
inline void CornersOf(const GridLevel& level, const float* pos, Corners& out) {
  __m512 xyz[3];
  LoadPositions(pos, xyz);
  const __m512 zero = _mm512_setzero_ps(), one = _mm512_set1_ps(1.0f);
  const __m512 res = _mm512_set1_ps(static_cast<float>(level.res));
  const __m512i last = _mm512_set1_epi32(static_cast<int>(level.res - 1));
  __m512i cell[3];
  for (int a = 0; a < 3; ++a) {
    out.inside[a] =
        _mm512_cmp_ps_mask(xyz[a], zero, _CMP_GT_OQ) & _mm512_cmp_ps_mask(xyz[a], one, _CMP_LT_OQ);
    // max returns its second operand for NaN: NaN and -Inf clamp to 0, as ClampUnit.
    const __m512 u = _mm512_min_ps(_mm512_max_ps(xyz[a], zero), one);
    const __m512 p = _mm512_mul_ps(u, res);
    cell[a] = _mm512_min_epu32(_mm512_cvttps_epu32(p), last);
    out.frac[a] = _mm512_sub_ps(p, _mm512_cvtepu32_ps(cell[a]));
  }
  if constexpr (kDense) {
    const int side = static_cast<int>(level.res + 1), plane = side * side;
    const __m512i base =
        _mm512_add_epi32(cell[0], _mm512_add_epi32(_mm512_mullo_epi32(cell[1], _mm512_set1_epi32(side)),
                                                   _mm512_mullo_epi32(cell[2], _mm512_set1_epi32(plane))));
    for (int k = 0; k < 8; ++k) {
      const int offset = (k & 1) + ((k >> 1) & 1) * side + ((k >> 2) & 1) * plane;
      out.slot[k] = _mm512_add_epi32(base, _mm512_set1_epi32(offset));
    }
  } else {
    const __m512i mask = _mm512_set1_epi32(static_cast<int>(level.entries - 1));
    const __m512i p1 = _mm512_set1_epi32(static_cast<int>(kHashPrimeY)),
                  p2 = _mm512_set1_epi32(static_cast<int>(kHashPrimeZ));
    const __m512i hx[2] = {cell[0], _mm512_add_epi32(cell[0], _mm512_set1_epi32(1))};
    const __m512i y0 = _mm512_mullo_epi32(cell[1], p1), z0 = _mm512_mullo_epi32(cell[2], p2);
    const __m512i hy[2] = {y0, _mm512_add_epi32(y0, p1)};
    const __m512i hz[2] = {z0, _mm512_add_epi32(z0, p2)};
    for (int k = 0; k < 8; ++k) {
      out.slot[k] =
          _mm512_and_si512(_mm512_xor_si512(_mm512_xor_si512(hx[k & 1], hy[(k >> 1) & 1]), hz[k >> 2]), mask);
    }
  }
  const __m512 wx[2] = {_mm512_sub_ps(one, out.frac[0]), out.frac[0]};
  const __m512 wy[2] = {_mm512_sub_ps(one, out.frac[1]), out.frac[1]};
  const __m512 wz[2] = {_mm512_sub_ps(one, out.frac[2]), out.frac[2]};
  for (int k = 0; k < 8; ++k)
    out.weight[k] = _mm512_mul_ps(_mm512_mul_ps(wx[k & 1], wy[(k >> 1) & 1]), wz[k >> 2]);
}

// Lanes 0..7 (half 0) or 8..15 (half 1) of v, each repeated twice: the layout of 8 gathered pairs.
inline __m512 DuplicateHalf(__m512 v, int half) {
  const __m512i lo = _mm512_setr_epi32(0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 5, 5, 6, 6, 7, 7);
  return _mm512_permutexvar_ps(half ? _mm512_add_epi32(lo, _mm512_set1_epi32(8)) : lo, v);
}

// The feature pairs of corner `slot` for 8 samples (half 0: lanes 0..7; half 1: lanes 8..15).
inline __m512 GatherPairs(const float* table, __m512i slot, int half) {
  const __m256i idx = half ? _mm512_extracti64x4_epi64(slot, 1) : _mm512_castsi512_si256(slot);
  return _mm512_castpd_ps(_mm512_i32gather_pd(idx, reinterpret_cast<const double*>(table), 8));
}

// Row offsets (in floats) of 8 samples, for 64-bit gathers and scatters of pairs.
inline __m256i RowOffsets(int stride, int half) {
  const __m256i j = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
  return _mm256_mullo_epi32(_mm256_add_epi32(j, _mm256_set1_epi32(8 * half)), _mm256_set1_epi32(stride));
}

// Forward of n samples (a multiple of 16): feat rows at feat + i * feat_stride receive 2 values.
template <bool kDense>
void ForwardLevelF2(const GridLevel& level, const float* table, const float* pos, int n, float* feat,
                    int feat_stride) {
  for (int i = 0; i < n; i += kBlock) {
    Corners c;
    CornersOf<kDense>(level, pos + 3 * i, c);
    for (int half = 0; half < 2; ++half) {
      __m512 acc = _mm512_setzero_ps();
      for (int k = 0; k < 8; ++k)
        acc = _mm512_fmadd_ps(DuplicateHalf(c.weight[k], half), GatherPairs(table, c.slot[k], half), acc);
      _mm512_i32scatter_pd(feat + static_cast<std::size_t>(i) * feat_stride, RowOffsets(feat_stride, half),
                           _mm512_castps_pd(acc), 4);
    }
  }
}

// Table scatter of n samples (a multiple of 16); with kPosition also adds the level's dL/dpos to dpos.
template <bool kDense, bool kPosition>
void ScatterLevelF2(const GridLevel& level, const float* pos, int n, const float* dfeat, int dfeat_stride,
                    const float* scale, float* grads, const float* table, float* dpos) {
  alignas(64) std::uint32_t slots[8][kBlock];
  alignas(64) float weights[8][kBlock];
  alignas(64) float g[3][kBlock];
  const float res = static_cast<float>(level.res);
  for (int i = 0; i < n; i += kBlock) {
    Corners c;
    CornersOf<kDense>(level, pos + 3 * i, c);
    const __m512 s = scale ? _mm512_loadu_ps(scale + i) : _mm512_set1_ps(1.0f);
    __m512 d[2];  // scale_i * dfeat_i as pairs, 8 samples per half
    for (int half = 0; half < 2; ++half) {
      const __m512 raw = _mm512_castpd_ps(_mm512_i32gather_pd(
          RowOffsets(dfeat_stride, half),
          reinterpret_cast<const double*>(dfeat + static_cast<std::size_t>(i) * dfeat_stride), 4));
      d[half] = _mm512_mul_ps(raw, DuplicateHalf(s, half));
    }
    for (int k = 0; k < 8; ++k) {
      _mm512_store_si512(slots[k], c.slot[k]);
      _mm512_store_ps(weights[k], c.weight[k]);
    }
    alignas(64) float pairs[2][2 * 8];
    _mm512_store_ps(pairs[0], d[0]);
    _mm512_store_ps(pairs[1], d[1]);
    // Read-modify-write of each corner's pair as one 64-bit load, FMA and store.
    for (int j = 0; j < kBlock; ++j) {
      const __m128 gj =
          _mm_castpd_ps(_mm_load_sd(reinterpret_cast<const double*>(pairs[j >> 3] + 2 * (j & 7))));
      for (int k = 0; k < 8; ++k) {
        double* v = reinterpret_cast<double*>(grads + 2 * std::size_t{slots[k][j]});
        const __m128 sum = _mm_fmadd_ps(_mm_set1_ps(weights[k][j]), gj, _mm_castpd_ps(_mm_load_sd(v)));
        _mm_store_sd(v, _mm_castps_pd(sum));
      }
    }
    if constexpr (kPosition) {
      // dot_k = (corner k's pair) . (scaled dfeat pair), for 16 samples in one vector.
      const __m512i even = _mm512_setr_epi32(0, 2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 22, 24, 26, 28, 30);
      __m512 dot[8];
      for (int k = 0; k < 8; ++k) {
        __m512 sums[2];
        for (int half = 0; half < 2; ++half) {
          const __m512 prod = _mm512_mul_ps(GatherPairs(table, c.slot[k], half), d[half]);
          sums[half] = _mm512_add_ps(prod, _mm512_permute_ps(prod, 0xB1));
        }
        dot[k] = _mm512_permutex2var_ps(sums[0], even, sums[1]);
      }
      const __m512 one = _mm512_set1_ps(1.0f);
      const __m512 wx[2] = {_mm512_sub_ps(one, c.frac[0]), c.frac[0]};
      const __m512 wy[2] = {_mm512_sub_ps(one, c.frac[1]), c.frac[1]};
      const __m512 wz[2] = {_mm512_sub_ps(one, c.frac[2]), c.frac[2]};
      __m512 grad[3] = {_mm512_setzero_ps(), _mm512_setzero_ps(), _mm512_setzero_ps()};
      for (int k = 0; k < 8; k += 2) {
        grad[0] = _mm512_fmadd_ps(_mm512_mul_ps(wy[(k >> 1) & 1], wz[k >> 2]),
                                  _mm512_sub_ps(dot[k + 1], dot[k]), grad[0]);
      }
      for (int j = 0; j < 4; ++j) {
        const int k = (j & 1) | ((j >> 1) << 2);
        grad[1] =
            _mm512_fmadd_ps(_mm512_mul_ps(wx[k & 1], wz[k >> 2]), _mm512_sub_ps(dot[k + 2], dot[k]), grad[1]);
      }
      for (int k = 0; k < 4; ++k) {
        grad[2] =
            _mm512_fmadd_ps(_mm512_mul_ps(wx[k & 1], wy[k >> 1]), _mm512_sub_ps(dot[k + 4], dot[k]), grad[2]);
      }
      for (int a = 0; a < 3; ++a) {
        _mm512_store_ps(g[a], _mm512_maskz_mul_ps(c.inside[a], grad[a], _mm512_set1_ps(res)));
      }
      float* out = dpos + 3 * static_cast<std::size_t>(i);
      for (int j = 0; j < kBlock; ++j) {
        for (int a = 0; a < 3; ++a) out[3 * j + a] += g[a][j];
      }
    }
  }
}

}  // namespace endorecon::field::simd

#endif
