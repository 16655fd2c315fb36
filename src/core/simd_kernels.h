// SPDX-License-Identifier: GPL-3.0-or-later
// Private to src/core: the loops that have a CPU-specific version. The *Avx2 kernels (the
// *_avx2.cpp files, compiled with -mavx2 -mfma on x86-64) run only when cpuRunsAvx2Kernels()
// is true; elsewhere those files hold stubs that are never called.
#pragma once

#include "oefmt/simd_kernel.h"

namespace oefmt {
namespace detail {

/// Whether `kernel` means the AVX2 kernels on this CPU. (`static`: see sampleLine.)
static inline bool runsAvx2(SimdKernel kernel) {
  return kernel == SimdKernel::kAuto && cpuRunsAvx2Kernels();
}

/// Bilinear samples along a line of the source (a warp row, a polar or log-polar ray):
/// column c samples (sx0 + dx t_c, sy0 + dy t_c), t_c = positions[c] (or c when positions is
/// null), and out[c] = row_weight * taper[c] * (bilinear - offset) (taper null: row_weight);
/// neighbours outside the source count as `offset`, i.e. 0 after the subtraction.
struct LineSamples {
  const float* source;
  int stride, cols, rows;
  float sx0, sy0, dx, dy;
  const float* positions;
  float row_weight;
  const float* taper;
  float offset;
  int count;
  float* out;
};
void sampleLinePortable(const LineSamples& line);  // line_sampling.cpp (SSE / NEON)
void sampleLineAvx2(const LineSamples& line);      // line_sampling_avx2.cpp
// `static`: a copy of this inline dispatcher emitted by an -mavx2 file can never serve others.
static inline void sampleLine(const LineSamples& line, bool avx2) {
  if (avx2) {
    sampleLineAvx2(line);
  } else {
    sampleLinePortable(line);
  }
}

/// `count` interleaved complex values: out = p * conj(q) / |p * conj(q)| (q not conjugated
/// when conjugate_sign is -1), element i times factor, and times (-1)^i when `alternate`.
void crossPowerRowAvx2(const float* p, const float* q, float* out, int count,
                       float conjugate_sign, float factor, bool alternate);

/// The same, each value also weighted by its share of signal in both spectra,
/// max(0, 1 - p_noise / |p|^2) max(0, 1 - q_noise / |q|^2).
void crossPowerRowWeightedAvx2(const float* p, const float* q, float* out, int count,
                               float conjugate_sign, float factor, bool alternate, float p_noise,
                               float q_noise);

/// out[i] = |z_i| for `count` interleaved complex values.
void magnitudeRowAvx2(const float* complex_values, int count, float* out);

/// What findPeak and prepareImage gather from each row: its extremes (a NaN is skipped, as
/// std::max skips it) and the sums of v, |v| and v^2 (a NaN carries through).
struct RowStats {
  float max, min, sum, abs_sum, square_sum;
};
/// The RowStats of `count` >= 1 floats.
RowStats rowStatsPortable(const float* row, int count);  // row_stats.cpp
RowStats rowStatsAvx2(const float* row, int count);      // spectral_avx2.cpp
static inline RowStats rowStats(const float* row, int count, bool avx2) {
  return avx2 ? rowStatsAvx2(row, count) : rowStatsPortable(row, count);
}
/// The RowStats of `rows` rows of `cols` >= 1 floats, `stride` floats apart, combined: the
/// extremes, and the rows' sums added in double.
struct SurfaceTotals {
  float max, min;
  double sum, abs_sum, square_sum;
};
SurfaceTotals surfaceTotals(const float* first_row, int stride, int rows, int cols, bool avx2);  // row_stats.cpp

}  // namespace detail
}  // namespace oefmt
