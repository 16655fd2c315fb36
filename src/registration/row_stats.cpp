// SPDX-License-Identifier: GPL-3.0-or-later
// The portable per-row statistics (the AVX2 kernel in spectral_avx2.cpp computes the same).
#include <algorithm>
#include <cmath>
#include <cstddef>

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

SurfaceTotals surfaceTotals(const float* first_row, int stride, int rows, int cols, bool avx2) {
  SurfaceTotals totals{first_row[0], first_row[0], 0.0, 0.0, 0.0};
  for (int r = 0; r < rows; ++r) {
    const RowStats row = rowStats(first_row + static_cast<std::ptrdiff_t>(r) * stride, cols, avx2);
    totals.max = std::max(totals.max, row.max);
    totals.min = std::min(totals.min, row.min);
    totals.sum += row.sum;
    totals.abs_sum += row.abs_sum;
    totals.square_sum += row.square_sum;
  }
  return totals;
}

}  // namespace detail
}  // namespace oefmt
