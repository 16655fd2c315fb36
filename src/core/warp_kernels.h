// SPDX-License-Identifier: GPL-3.0-or-later
// Private to src/core: one output row of the similarity warp, for the CPU-specific kernels.
#pragma once

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

/// AVX2 + FMA kernel (warp_avx2.cpp); call only when cpuHasAvx2Fma().
void warpRowAvx2(const WarpRow& row);

/// True when the CPU runs AVX2 and FMA code.
bool cpuHasAvx2Fma();

}  // namespace detail
}  // namespace oefmt
