// SPDX-License-Identifier: GPL-3.0-or-later
// Private to src/registration: the loops that have a CPU-specific version. The *Avx2 kernels (the
// *_avx2.cpp files, compiled with -mavx2 -mfma on x86-64) run only when cpuRunsAvx2Kernels()
// is true; elsewhere those files hold stubs that are never called.
#pragma once

#include "oefmt/registration/simd_kernel_choice.h"

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

/// Keeps 0/0 out of the cross power without a branch: a vanished product stays 0.
constexpr float kTinyMagnitudeSquared = 1e-30f;

/// Element i of the cross power below, `factor` already the one of its parity: the portable
/// loop's body and the AVX2 kernels' tails, so that all compute the same. (`static`: see
/// sampleLine.)
static inline void crossPowerElement(const float* p, const float* q, float* out, int i,
                                     float conjugate_sign, float factor) {
  const float pr = p[2 * i], pi = p[2 * i + 1];
  const float qr = q[2 * i], qi = conjugate_sign * q[2 * i + 1];
  const float re = pr * qr + pi * qi;
  const float im = pi * qr - pr * qi;
  const float scale = factor / __builtin_sqrtf(re * re + im * im + kTinyMagnitudeSquared);
  out[2 * i] = re * scale;
  out[2 * i + 1] = im * scale;
}

/// The same, weighted by the element's share of signal in both spectra (see
/// crossPowerRowWeightedAvx2).
static inline void weightedCrossPowerElement(const float* p, const float* q, float* out, int i,
                                             float conjugate_sign, float factor, float p_noise,
                                             float q_noise) {
  const float pr = p[2 * i], pi = p[2 * i + 1];
  const float qr = q[2 * i], qi = conjugate_sign * q[2 * i + 1];
  const float re = pr * qr + pi * qi;
  const float im = pi * qr - pr * qi;
  const float scale = factor / __builtin_sqrtf(re * re + im * im + kTinyMagnitudeSquared);
  const float wp = __builtin_fmaxf(0.0f, 1.0f - p_noise / (pr * pr + pi * pi + kTinyMagnitudeSquared));
  const float wq = __builtin_fmaxf(0.0f, 1.0f - q_noise / (qr * qr + qi * qi + kTinyMagnitudeSquared));
  out[2 * i] = re * (scale * (wp * wq));
  out[2 * i + 1] = im * (scale * (wp * wq));
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
