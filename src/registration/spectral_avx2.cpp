// SPDX-License-Identifier: GPL-3.0-or-later
// AVX2 + FMA kernels of the per-frequency loops (cross power, magnitude) and of the surface
// statistics of the peak search. Compiled with -mavx2 -mfma (CMakeLists.txt) and called only on CPUs that have
// both; nothing but intrinsics, builtins and plain types in here (see line_sampling_avx2.cpp for why).
#if defined(__x86_64__)
#include <immintrin.h>

#include "avx2_lanes.h"
#include "simd_kernels.h"

namespace oefmt {
namespace detail {
// p * conj(q) (p * q when sign's odd lanes are -1) of four interleaved complex values.
static inline __m256 complexProducts(const float* p, const float* q, __m256 sign) {
  const __m256 pv = _mm256_loadu_ps(p);
  const __m256 qv = _mm256_mul_ps(_mm256_loadu_ps(q), sign);
  const __m256 swapped = _mm256_permute_ps(pv, 0xB1);  // (pi, pr) pairs
  // Even lanes: pr qr + pi qi; odd lanes: pi qr - pr qi.
  return _mm256_fmsubadd_ps(pv, _mm256_moveldup_ps(qv), _mm256_mul_ps(swapped, _mm256_movehdup_ps(qv)));
}

// Each lane's squared magnitude of its complex value of four: re^2 + im^2 in both of its lanes.
static inline __m256 pairNorms(__m256 v) {
  const __m256 squares = _mm256_mul_ps(v, v);
  return _mm256_add_ps(squares, _mm256_permute_ps(squares, 0xB1));
}

void crossPowerRowAvx2(const float* p, const float* q, float* out, int count,
                       float conjugate_sign, float factor, bool alternate) {
  const float odd_factor = alternate ? -factor : factor;
  const __m256 sign = _mm256_setr_ps(1.0f, conjugate_sign, 1.0f, conjugate_sign, 1.0f,
                                     conjugate_sign, 1.0f, conjugate_sign);
  const __m256 tiny = _mm256_set1_ps(kTinyMagnitudeSquared);
  int i = 0;
  // Eight complex values per step: their eight norms in one vector, so that each square root
  // and division serves one value (the four-value step below computes each twice). The same
  // operations on each value as the other loops: the same bits.
  {
    // hadd order of the norms: values 0 1 4 5 | 2 3 6 7 of the step, parities alternate.
    const __m256 factors = _mm256_setr_ps(factor, odd_factor, factor, odd_factor, factor,
                                          odd_factor, factor, odd_factor);
    for (; i + 8 <= count; i += 8) {
      const __m256 low = complexProducts(p + 2 * i, q + 2 * i, sign);
      const __m256 high = complexProducts(p + 2 * i + 8, q + 2 * i + 8, sign);
      const __m256 norms = _mm256_hadd_ps(_mm256_mul_ps(low, low), _mm256_mul_ps(high, high));
      const __m256 scales = _mm256_div_ps(factors, _mm256_sqrt_ps(_mm256_add_ps(norms, tiny)));
      _mm256_storeu_ps(out + 2 * i, _mm256_mul_ps(low, _mm256_unpacklo_ps(scales, scales)));
      _mm256_storeu_ps(out + 2 * i + 8, _mm256_mul_ps(high, _mm256_unpackhi_ps(scales, scales)));
    }
  }
  // Four complex values per step, starting at an even index.
  const __m256 factors = _mm256_setr_ps(factor, factor, odd_factor, odd_factor, factor, factor,
                                        odd_factor, odd_factor);
  for (; i + 4 <= count; i += 4) {
    const __m256 product = complexProducts(p + 2 * i, q + 2 * i, sign);
    const __m256 scale = _mm256_div_ps(factors, _mm256_sqrt_ps(_mm256_add_ps(pairNorms(product), tiny)));
    _mm256_storeu_ps(out + 2 * i, _mm256_mul_ps(product, scale));
  }
  for (; i < count; ++i) crossPowerElement(p, q, out, i, conjugate_sign, (i & 1) ? odd_factor : factor);
}

void crossPowerRowWeightedAvx2(const float* p, const float* q, float* out, int count,
                               float conjugate_sign, float factor, bool alternate, float p_noise,
                               float q_noise) {
  const float odd_factor = alternate ? -factor : factor;
  const __m256 sign = _mm256_setr_ps(1.0f, conjugate_sign, 1.0f, conjugate_sign, 1.0f,
                                     conjugate_sign, 1.0f, conjugate_sign);
  const __m256 tiny = _mm256_set1_ps(kTinyMagnitudeSquared);
  const __m256 one = _mm256_set1_ps(1.0f), zero = _mm256_setzero_ps();
  const __m256 pn = _mm256_set1_ps(p_noise), qn = _mm256_set1_ps(q_noise);
  const __m256 factors = _mm256_setr_ps(factor, factor, odd_factor, odd_factor, factor, factor,
                                        odd_factor, odd_factor);
  int i = 0;
  for (; i + 4 <= count; i += 4) {
    const __m256 product = complexProducts(p + 2 * i, q + 2 * i, sign);
    const __m256 scale = _mm256_div_ps(factors, _mm256_sqrt_ps(_mm256_add_ps(pairNorms(product), tiny)));
    const __m256 wp = _mm256_max_ps(zero, _mm256_sub_ps(one, _mm256_div_ps(pn, _mm256_add_ps(pairNorms(_mm256_loadu_ps(p + 2 * i)), tiny))));
    const __m256 wq = _mm256_max_ps(zero, _mm256_sub_ps(one, _mm256_div_ps(qn, _mm256_add_ps(pairNorms(_mm256_loadu_ps(q + 2 * i)), tiny))));
    _mm256_storeu_ps(out + 2 * i, _mm256_mul_ps(product, _mm256_mul_ps(scale, _mm256_mul_ps(wp, wq))));
  }
  for (; i < count; ++i) {
    weightedCrossPowerElement(p, q, out, i, conjugate_sign, (i & 1) ? odd_factor : factor, p_noise, q_noise);
  }
}

void magnitudeRowAvx2(const float* complex_values, int count, float* out) {
  int i = 0;
  for (; i + 8 <= count; i += 8) {
    __m256 re, im;
    deinterleave(_mm256_loadu_ps(complex_values + 2 * i),
                 _mm256_loadu_ps(complex_values + 2 * i + 8), re, im);
    _mm256_storeu_ps(out + i, _mm256_sqrt_ps(_mm256_fmadd_ps(re, re, _mm256_mul_ps(im, im))));
  }
  for (; i < count; ++i) {
    const float re = complex_values[2 * i], im = complex_values[2 * i + 1];
    out[i] = __builtin_sqrtf(re * re + im * im);
  }
}

RowStats rowStatsAvx2(const float* row, int count) {
  const __m256 sign_bit = _mm256_set1_ps(-0.0f);
  __m256 maxima = _mm256_set1_ps(row[0]), minima = maxima;
  __m256 sums = _mm256_setzero_ps(), abs_sums = _mm256_setzero_ps(), square_sums = _mm256_setzero_ps();
  int c = 0;
  for (; c + 8 <= count; c += 8) {
    const __m256 v = _mm256_loadu_ps(row + c);
    // max/min return their second operand when one is NaN: the running value, as std::max.
    maxima = _mm256_max_ps(v, maxima);
    minima = _mm256_min_ps(v, minima);
    sums = _mm256_add_ps(sums, v);
    abs_sums = _mm256_add_ps(abs_sums, _mm256_andnot_ps(sign_bit, v));
    square_sums = _mm256_fmadd_ps(v, v, square_sums);
  }
  alignas(32) float max_lanes[8], min_lanes[8], sum_lanes[8], abs_lanes[8], square_lanes[8];
  _mm256_store_ps(max_lanes, maxima);
  _mm256_store_ps(min_lanes, minima);
  _mm256_store_ps(sum_lanes, sums);
  _mm256_store_ps(abs_lanes, abs_sums);
  _mm256_store_ps(square_lanes, square_sums);
  RowStats stats{max_lanes[0], min_lanes[0], 0.0f, 0.0f, 0.0f};
  for (int lane = 0; lane < 8; ++lane) {
    stats.max = max_lanes[lane] > stats.max ? max_lanes[lane] : stats.max;
    stats.min = min_lanes[lane] < stats.min ? min_lanes[lane] : stats.min;
    stats.sum += sum_lanes[lane];
    stats.abs_sum += abs_lanes[lane];
    stats.square_sum += square_lanes[lane];
  }
  for (; c < count; ++c) {
    const float v = row[c];
    stats.max = v > stats.max ? v : stats.max;
    stats.min = v < stats.min ? v : stats.min;
    stats.sum += v;
    stats.abs_sum += __builtin_fabsf(v);
    stats.square_sum += v * v;
  }
  return stats;
}

}  // namespace detail
}  // namespace oefmt

#else  // not x86-64: never called (cpuRunsAvx2Kernels() is false there); defined for the linker.

#include <cstdlib>

#include "simd_kernels.h"

namespace oefmt {
namespace detail {

void crossPowerRowAvx2(const float*, const float*, float*, int, float, float, bool) { std::abort(); }
void crossPowerRowWeightedAvx2(const float*, const float*, float*, int, float, float, bool, float, float) {
  std::abort();
}
void magnitudeRowAvx2(const float*, int, float*) { std::abort(); }
RowStats rowStatsAvx2(const float*, int) { std::abort(); }

}  // namespace detail
}  // namespace oefmt

#endif
