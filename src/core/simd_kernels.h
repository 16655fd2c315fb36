// SPDX-License-Identifier: GPL-3.0-or-later
// Private to src/core: the AVX2 + FMA kernels (the *_avx2.cpp files, compiled with -mavx2
// -mfma) and what they are given. Call them only when cpuRunsAvx2Kernels() is true.
#pragma once

#include <cstdint>

namespace oefmt {
namespace detail {

/// Row y of warpSimilarityWindowed: source point of output column x is
/// (sx0 + a00 x, sy0 + a10 x); out[x] = row_weight * taper[x] * (bilinear - offset).
struct WarpRow {
  const float* source;
  int stride, cols, rows;
  float sx0, sy0, a00, a10;
  float row_weight;
  const float* taper;
  float offset;
  float* out;
};
void warpRowAvx2(const WarpRow& row);

/// One row of a BilinearRemapTable: out[c] = w0 p[0] + w1 p[1] + w2 p[stride] + w3 p[stride + 1]
/// with p = source + offset[c].
struct RemapRow {
  const float* source;
  int stride;
  const std::int32_t* offset;
  const float* weight[4];
  int count;
  float* out;
};
void remapRowAvx2(const RemapRow& row);

/// `count` interleaved complex values: out = p * conj(q) / |p * conj(q)| (q not conjugated
/// when conjugate_sign is -1), element i times factor, and times (-1)^i when `alternate`.
void crossPowerRowAvx2(const float* p, const float* q, float* out, int count,
                       float conjugate_sign, float factor, bool alternate);

/// out[i] = |z_i| for `count` interleaved complex values.
void magnitudeRowAvx2(const float* complex_values, int count, float* out);

}  // namespace detail
}  // namespace oefmt
