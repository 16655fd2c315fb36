// SPDX-License-Identifier: GPL-3.0-or-later
// The portable per-row statistics (the AVX2 kernel in spectral_avx2.cpp computes the same).
#include <algorithm>
#include <cmath>

#include "simd_kernels.h"

namespace oefmt {
namespace detail {

RowStats rowStatsPortable(const float* row, int count) {
  float row_max = row[0], row_min = row[0], sum = 0.0f, abs_sum = 0.0f, square_sum = 0.0f;
#pragma omp simd reduction(max : row_max) reduction(min : row_min) reduction(+ : sum, abs_sum, square_sum)
  for (int c = 0; c < count; ++c) {
    const float v = row[c];
    row_max = std::max(row_max, v);
    row_min = std::min(row_min, v);
    sum += v;
    abs_sum += std::fabs(v);
    square_sum += v * v;
  }
  return {row_max, row_min, sum, abs_sum, square_sum};
}

}  // namespace detail
}  // namespace oefmt
