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

namespace {

// Samples from .. to - 1 one at a time (a group of eight that reaches past the border, the
// tail). Out of line, so that the registers of the vector loop are not spilled around it.
[[gnu::noinline]] void sampleOneByOne(const LineSamples& line, int from, int to) {
  for (int c = from; c < to; ++c) sampleLineAt(line, c);
}

// The loop, compiled once per kind of line: positions given (polar and log-polar rays) or not
// (warp rows), taper given (warp rows) or not. Every field is read once, into a register.
template <bool kPositions, bool kTaper>
void sampleLineLoop(const LineSamples& line) {
  const float* const src = line.source;
  const float* const positions = line.positions;
  const float* const taper = line.taper;
  float* const out = line.out;
  const int count = line.count, stride = line.stride;
  const __m256 dx = _mm256_set1_ps(line.dx), dy = _mm256_set1_ps(line.dy);
  const __m256 sx0 = _mm256_set1_ps(line.sx0), sy0 = _mm256_set1_ps(line.sy0);
  const __m256 offset = _mm256_set1_ps(line.offset), weight = _mm256_set1_ps(line.row_weight);
  // Unsigned bounds: a negative index (or NaN, which converts to INT_MIN) is above them.
  const __m256i max_x = _mm256_set1_epi32(line.cols - 2), max_y = _mm256_set1_epi32(line.rows - 2);
  const __m256i vstride = _mm256_set1_epi32(stride);
  const __m256 eight = _mm256_set1_ps(8.0f);
  // Column numbers as floats (exact below 2^24), stepped by 8.
  __m256 columns = _mm256_setr_ps(0.0f, 1.0f, 2.0f, 3.0f, 4.0f, 5.0f, 6.0f, 7.0f);
  int c = 0;
  for (; c + 8 <= count; c += 8, columns = _mm256_add_ps(columns, eight)) {
    const __m256 t = kPositions ? _mm256_loadu_ps(positions + c) : columns;
    const __m256 sx = _mm256_fmadd_ps(dx, t, sx0);
    const __m256 sy = _mm256_fmadd_ps(dy, t, sy0);
    const __m256 floor_x = _mm256_floor_ps(sx), floor_y = _mm256_floor_ps(sy);
    const __m256i ix = _mm256_cvttps_epi32(floor_x), iy = _mm256_cvttps_epi32(floor_y);
    // The whole 2 x 2 neighbourhood inside: 0 <= ix <= cols - 2 and 0 <= iy <= rows - 2.
    const __m256i inside = _mm256_and_si256(_mm256_cmpeq_epi32(_mm256_min_epu32(ix, max_x), ix),
                                            _mm256_cmpeq_epi32(_mm256_min_epu32(iy, max_y), iy));
    if (!_mm256_testc_si256(inside, _mm256_set1_epi32(-1))) {
      sampleOneByOne(line, c, c + 8);
      continue;
    }
    const __m256 fx = _mm256_sub_ps(sx, floor_x), fy = _mm256_sub_ps(sy, floor_y);
    const __m256i index = _mm256_add_epi32(_mm256_mullo_epi32(iy, vstride), ix);
    __m256 p00, p01, p10, p11;
    loadNeighbours(src, stride, index, p00, p01, p10, p11);
    const __m256 top = _mm256_fmadd_ps(fx, _mm256_sub_ps(p01, p00), p00);
    const __m256 bottom = _mm256_fmadd_ps(fx, _mm256_sub_ps(p11, p10), p10);
    const __m256 value = _mm256_fmadd_ps(fy, _mm256_sub_ps(bottom, top), top);
    const __m256 w = kTaper ? _mm256_mul_ps(_mm256_loadu_ps(taper + c), weight) : weight;
    _mm256_storeu_ps(out + c, _mm256_mul_ps(_mm256_sub_ps(value, offset), w));
  }
  // The compiler leaves out its own vzeroupper before the tail call below: the callers' legacy
  // SSE code (everything built for the portable target) would then run with the upper halves
  // of the vector registers in use, and on some CPUs every such instruction waits on them.
  _mm256_zeroupper();
  sampleOneByOne(line, c, count);
}

}  // namespace

void sampleLineAvx2(const LineSamples& line) {
  if (line.cols < 2 || line.rows < 2) {  // no 2 x 2 neighbourhood: the border path throughout
    sampleOneByOne(line, 0, line.count);
  } else if (line.positions != nullptr) {
    line.taper != nullptr ? sampleLineLoop<true, true>(line) : sampleLineLoop<true, false>(line);
  } else {
    line.taper != nullptr ? sampleLineLoop<false, true>(line) : sampleLineLoop<false, false>(line);
  }
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
