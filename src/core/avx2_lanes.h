// SPDX-License-Identifier: GPL-3.0-or-later
// Private to the *_avx2.cpp kernels: lane shuffles they share. Include only from files
// compiled with -mavx2; `static` keeps each copy inside its (AVX2) translation unit.
#pragma once

#include <immintrin.h>

namespace oefmt {
namespace detail {

/// The even and the odd floats of a:b, in order: (a0 a2 a4 a6 b0 b2 b4 b6), (a1 a3 ... b7).
/// Splits interleaved complex values, or the pairs a 64-bit gather fetched.
static inline void deinterleave(__m256 a, __m256 b, __m256& even, __m256& odd) {
  const __m256i order = _mm256_setr_epi32(0, 1, 4, 5, 2, 3, 6, 7);
  even = _mm256_permutevar8x32_ps(_mm256_shuffle_ps(a, b, 0x88), order);
  odd = _mm256_permutevar8x32_ps(_mm256_shuffle_ps(a, b, 0xDD), order);
}

/// Four pairs of adjacent floats, at float offsets `index` from `base` (a 64-bit gather: the
/// two horizontal neighbours of a bilinear sample in one element). The masked form with a
/// zero source: GCC 12 warns that the plain one's undefined source may be used.
static inline __m256 gatherPairs(const float* base, __m128i index) {
  const __m256d all = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
  return _mm256_castpd_ps(_mm256_mask_i32gather_pd(_mm256_setzero_pd(),
                                                   reinterpret_cast<const double*>(base), index,
                                                   all, 4));
}

/// Bilinear neighbours p00, p01 (row `top`) and p10, p11 (row `top` + stride) of eight
/// samples at float offsets `index`.
static inline void gatherNeighbours(const float* top, int stride, __m256i index, __m256& p00,
                                    __m256& p01, __m256& p10, __m256& p11) {
  const __m128i low = _mm256_castsi256_si128(index), high = _mm256_extracti128_si256(index, 1);
  deinterleave(gatherPairs(top, low), gatherPairs(top, high), p00, p01);
  deinterleave(gatherPairs(top + stride, low), gatherPairs(top + stride, high), p10, p11);
}

}  // namespace detail
}  // namespace oefmt
