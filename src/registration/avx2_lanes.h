// SPDX-License-Identifier: GPL-3.0-or-later
// Private to the *_avx2.cpp kernels: lane shuffles they share. Include only from files
// compiled with -mavx2; `static` keeps each copy inside its (AVX2) translation unit.
#pragma once

#include <immintrin.h>

#include <cstring>

namespace oefmt {
namespace detail {

/// The even and the odd floats of a:b, in order: (a0 a2 a4 a6 b0 b2 b4 b6), (a1 a3 ... b7).
/// Splits interleaved complex values.
static inline void deinterleave(__m256 a, __m256 b, __m256& even, __m256& odd) {
  const __m256i order = _mm256_setr_epi32(0, 1, 4, 5, 2, 3, 6, 7);
  even = _mm256_permutevar8x32_ps(_mm256_shuffle_ps(a, b, 0x88), order);
  odd = _mm256_permutevar8x32_ps(_mm256_shuffle_ps(a, b, 0xDD), order);
}

/// Four pairs of adjacent floats, at float offsets `at0`, `at1` (the low 128 bits) and `at2`,
/// `at3` (the high 128 bits) from `base`: the two horizontal neighbours of a bilinear sample in
/// one 64-bit load each. Plain loads, not a hardware gather: the gathers were slower on the AMD
/// Zen 3 host the kernels were tuned on, and the loads give the same bits (doc/performance.md).
/// The low pair goes through memcpy (floats are not read through a double pointer; it compiles to
/// the same vmovq as _mm_load_sd); movhps's intrinsic reads through a may-alias type.
static inline __m256 loadPairs(const float* base, unsigned at0, unsigned at1, unsigned at2,
                               unsigned at3) {
  auto low64 = [base](unsigned at) {
    double pair;
    std::memcpy(&pair, base + at, sizeof pair);
    return _mm_castpd_ps(_mm_set_sd(pair));
  };
  auto high64 = [base](unsigned at) { return reinterpret_cast<const __m64*>(base + at); };
  const __m128 low = _mm_loadh_pi(low64(at0), high64(at1));
  const __m128 high = _mm_loadh_pi(low64(at2), high64(at3));
  return _mm256_insertf128_ps(_mm256_castps128_ps256(low), high, 1);
}

/// Bilinear neighbours p00, p01 (row `top`) and p10, p11 (row `top` + stride) of eight
/// samples at float offsets `index` (all >= 0). Samples 0, 1, 4, 5 are loaded into one vector
/// and 2, 3, 6, 7 into the other, so that the in-lane shuffle that splits left from right
/// neighbours leaves the samples in order (no lane-crossing permute).
static inline void loadNeighbours(const float* top, int stride, __m256i index, __m256& p00,
                                  __m256& p01, __m256& p10, __m256& p11) {
  alignas(32) unsigned at[8];
  _mm256_store_si256(reinterpret_cast<__m256i*>(at), index);
  const float* bottom = top + stride;
  const __m256 top_a = loadPairs(top, at[0], at[1], at[4], at[5]);
  const __m256 top_b = loadPairs(top, at[2], at[3], at[6], at[7]);
  const __m256 bottom_a = loadPairs(bottom, at[0], at[1], at[4], at[5]);
  const __m256 bottom_b = loadPairs(bottom, at[2], at[3], at[6], at[7]);
  p00 = _mm256_shuffle_ps(top_a, top_b, 0x88);
  p01 = _mm256_shuffle_ps(top_a, top_b, 0xDD);
  p10 = _mm256_shuffle_ps(bottom_a, bottom_b, 0x88);
  p11 = _mm256_shuffle_ps(bottom_a, bottom_b, 0xDD);
}

}  // namespace detail
}  // namespace oefmt
