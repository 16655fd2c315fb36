// SPDX-License-Identifier: GPL-3.0-or-later
// AVX2 + FMA kernel of the line sampler (warp rows, polar and log-polar rays): eight samples per
// step, their neighbours fetched with 64-bit loads. Compiled with -mavx2 -mfma (CMakeLists.txt)
// and called only on CPUs that have both. Nothing but intrinsics and plain types in here: an
// inline function from a shared header, compiled with AVX2 in this file, could otherwise be the
// copy the linker keeps for portable callers.
#if defined(__x86_64__)
#include <immintrin.h>

#include "avx2_lanes.h"
#include "bilinear_sample.h"

namespace oefmt {
namespace detail {

void sampleLineAvx2(const LineSamples& line) {
  const float* src = line.source;
  const int cols = line.cols, rows = line.rows, stride = line.stride;
  const __m256 lanes = _mm256_setr_ps(0.0f, 1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f);
  const __m256 dx = _mm256_set1_ps(line.dx), dy = _mm256_set1_ps(line.dy);
  const __m256 sx0 = _mm256_set1_ps(line.sx0), sy0 = _mm256_set1_ps(line.sy0);
  const __m256 offset = _mm256_set1_ps(line.offset), weight = _mm256_set1_ps(line.row_weight);
  const __m256i zero = _mm256_setzero_si256();
  const __m256i max_x = _mm256_set1_epi32(cols - 2), max_y = _mm256_set1_epi32(rows - 2);
  const __m256i vstride = _mm256_set1_epi32(stride);
  int c = 0;
  for (; c + 8 <= line.count; c += 8) {
    const __m256 t = line.positions ? _mm256_loadu_ps(line.positions + c)
                                    : _mm256_add_ps(_mm256_set1_ps(static_cast<float>(c)), lanes);
    const __m256 sx = _mm256_fmadd_ps(dx, t, sx0);
    const __m256 sy = _mm256_fmadd_ps(dy, t, sy0);
    const __m256 floor_x = _mm256_floor_ps(sx), floor_y = _mm256_floor_ps(sy);
    const __m256i ix = _mm256_cvttps_epi32(floor_x), iy = _mm256_cvttps_epi32(floor_y);
    // The whole 2 x 2 neighbourhood inside (NaN converts to INT_MIN: outside).
    const __m256i outside = _mm256_or_si256(
        _mm256_or_si256(_mm256_cmpgt_epi32(zero, ix), _mm256_cmpgt_epi32(ix, max_x)),
        _mm256_or_si256(_mm256_cmpgt_epi32(zero, iy), _mm256_cmpgt_epi32(iy, max_y)));
    if (!_mm256_testz_si256(outside, outside)) {
      for (int k = c; k < c + 8; ++k) sampleLineAt(line, k);
      continue;
    }
    const __m256 fx = _mm256_sub_ps(sx, floor_x), fy = _mm256_sub_ps(sy, floor_y);
    const __m256i index = _mm256_add_epi32(_mm256_mullo_epi32(iy, vstride), ix);
    __m256 p00, p01, p10, p11;
    loadNeighbours(src, stride, index, p00, p01, p10, p11);
    const __m256 top = _mm256_fmadd_ps(fx, _mm256_sub_ps(p01, p00), p00);
    const __m256 bottom = _mm256_fmadd_ps(fx, _mm256_sub_ps(p11, p10), p10);
    const __m256 value = _mm256_fmadd_ps(fy, _mm256_sub_ps(bottom, top), top);
    const __m256 w = line.taper ? _mm256_mul_ps(_mm256_loadu_ps(line.taper + c), weight) : weight;
    _mm256_storeu_ps(line.out + c, _mm256_mul_ps(_mm256_sub_ps(value, offset), w));
  }
  for (; c < line.count; ++c) sampleLineAt(line, c);
}

}  // namespace detail
}  // namespace oefmt

#else  // not x86-64: never called (cpuRunsAvx2Kernels() is false there); defined for the linker.

#include <cstdlib>

#include "simd_kernels.h"

namespace oefmt {
namespace detail {

void sampleLineAvx2(const LineSamples&) { std::abort(); }

}  // namespace detail
}  // namespace oefmt

#endif
