// SPDX-License-Identifier: GPL-3.0-or-later
// Private to src/registration: the scalar bilinear sample of the line sampler, shared by its portable
// and AVX2 kernels. `static` on purpose: each translation unit keeps its own copy, so
// the copy compiled with -mavx2 can never be the one the linker picks for portable code.
#pragma once

#include "simd_kernels.h"

namespace oefmt {
namespace detail {

// Bilinear sample less `offset`, with neighbours outside the source counted as `offset` (so
// that outside is 0 after the subtraction).
static inline float sampleBilinear(const float* src, int stride, int cols, int rows, float sx, float sy,
                                   float offset) {
  if (!(sx > -1.0f && sy > -1.0f && sx < cols && sy < rows)) return 0.0f;  // outside (or NaN)
  // floor for values > -1 without a libm call: truncate after shifting to positive.
  const int x0 = static_cast<int>(sx + 1.0f) - 1, y0 = static_cast<int>(sy + 1.0f) - 1;
  const float fx = sx - static_cast<float>(x0), fy = sy - static_cast<float>(y0);
  auto at = [&](int x, int y) -> float {
    return (x < 0 || y < 0 || x >= cols || y >= rows) ? 0.0f : src[y * stride + x] - offset;
  };
  const float top = at(x0, y0) + fx * (at(x0 + 1, y0) - at(x0, y0));
  const float bottom = at(x0, y0 + 1) + fx * (at(x0 + 1, y0 + 1) - at(x0, y0 + 1));
  return top + fy * (bottom - top);
}

/// Column c of a LineSamples, one sample at a time (the kernels' border and tail path).
static inline void sampleLineAt(const LineSamples& line, int c) {
  const float t = line.positions ? line.positions[c] : static_cast<float>(c);
  const float weight = line.taper ? line.row_weight * line.taper[c] : line.row_weight;
  line.out[c] = weight * sampleBilinear(line.source, line.stride, line.cols, line.rows,
                                        line.sx0 + line.dx * t, line.sy0 + line.dy * t, line.offset);
}

}  // namespace detail
}  // namespace oefmt
