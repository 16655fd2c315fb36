// SPDX-License-Identifier: GPL-3.0-or-later
// The CPU-specific kernels (AVX2 + FMA where the CPU has both) against the portable code: the
// same results up to float rounding, for row lengths that leave a scalar tail, and the same
// handling of vanished values. (On a CPU without AVX2 both sides are the portable code.)
#include <gtest/gtest.h>

#include <cmath>

#include "oefmt/fft.h"
#include "oefmt/phase_correlation.h"
#include "oefmt/remap_table.h"
#include "oefmt/spectra.h"

namespace oefmt {
namespace {

cv::Mat2f randomSpectrum(int rows, int cols, int seed) {
  cv::Mat2f spectrum(rows, cols);
  cv::RNG rng(seed);
  rng.fill(spectrum, cv::RNG::NORMAL, 0.0, 50.0);
  return spectrum;
}

TEST(SimdKernels, CrossPowerMatchesThePortableLoop) {
  // 33 complex columns: four-wide steps and a tail of one (as the real FFT's N/2 + 1).
  const cv::Mat2f newer = randomSpectrum(16, 33, 1);
  cv::Mat2f older = randomSpectrum(16, 33, 2);
  older(3, 5) = cv::Vec2f(0.0f, 0.0f);    // a vanished product gives 0, not NaN
  older(4, 32) = cv::Vec2f(0.0f, 0.0f);   // also in the tail
  for (const bool half_turn : {false, true}) {
    cv::Mat2f fast, portable, fast_centred, portable_centred;
    normalisedCrossPower(newer, older, fast, half_turn, SimdKernel::kAuto);
    normalisedCrossPower(newer, older, portable, half_turn, SimdKernel::kPortable);
    centredCrossPower(newer, older, fast_centred, half_turn, SimdKernel::kAuto);
    centredCrossPower(newer, older, portable_centred, half_turn, SimdKernel::kPortable);
    EXPECT_LT(cv::norm(fast, portable, cv::NORM_INF), 1e-6);
    EXPECT_LT(cv::norm(fast_centred, portable_centred, cv::NORM_INF), 1e-6 / (16.0 * 16.0));
    EXPECT_EQ(fast(3, 5), cv::Vec2f(0.0f, 0.0f));
    EXPECT_EQ(fast(4, 32), cv::Vec2f(0.0f, 0.0f));
    EXPECT_NEAR(std::hypot(fast(7, 9)[0], fast(7, 9)[1]), 1.0, 1e-6);
    // The centring sign alternates with the column (and the row).
    EXPECT_NEAR(fast_centred(2, 1)[0], -fast(2, 1)[0] / (16.0 * 16.0), 1e-9);
    EXPECT_NEAR(fast_centred(3, 1)[0], fast(3, 1)[0] / (16.0 * 16.0), 1e-9);
  }
}

TEST(SimdKernels, MagnitudeMatchesThePortableLoop) {
  const int n = 64;  // 33 stored columns: a tail of one after four eight-wide steps
  const cv::Mat2f spectrum = randomSpectrum(n, n / 2 + 1, 3);
  cv::Mat1f filter(n / 2 + 2, n);
  cv::randu(filter, 0.0f, 1.0f);
  cv::Mat1f fast, portable;
  upperHalfMagnitude(spectrum, filter, fast, SimdKernel::kAuto);
  upperHalfMagnitude(spectrum, filter, portable, SimdKernel::kPortable);
  EXPECT_LT(cv::norm(fast, portable, cv::NORM_INF), 1e-4);
  // Column fx >= 0 of centred row fy is |spectrum(fy mod N, fx)|; fx < 0 mirrors (-fx, -fy).
  const cv::Vec2f direct = spectrum(n - 3, 5), mirror = spectrum(3, 5);
  EXPECT_NEAR(fast(n / 2 - 3, n / 2 + 5), std::hypot(direct[0], direct[1]) * filter(n / 2 - 3, n / 2 + 5), 1e-3);
  EXPECT_NEAR(fast(n / 2 - 3, n / 2 - 5), std::hypot(mirror[0], mirror[1]) * filter(n / 2 - 3, n / 2 - 5), 1e-3);
}

TEST(SimdKernels, RemapMatchesThePortableLoop) {
  // 37 output columns (a tail after eight-wide steps), samples all over a 40 x 30 source and
  // beyond its border (outside neighbours weigh nothing).
  const cv::Size output(37, 23), source_size(40, 30);
  const BilinearRemapTable table(output, source_size, [](int r, int c) {
    return cv::Point2d(-1.5 + 1.17 * c + 0.05 * r, -0.7 + 1.41 * r - 0.03 * c);
  });
  cv::Mat1f source(source_size);
  cv::randu(source, -10.0f, 10.0f);
  cv::Mat1f fast, portable, fast_rows, portable_rows;
  table.apply(source, fast, SimdKernel::kAuto);
  table.apply(source, portable, SimdKernel::kPortable);
  EXPECT_LT(cv::norm(fast, portable, cv::NORM_INF), 1e-4);
  EXPECT_GT(cv::norm(portable, cv::NORM_INF), 1.0);
  table.applyRows(source, 20, 6, fast_rows, SimdKernel::kAuto);  // wraps past the last row
  table.applyRows(source, 20, 6, portable_rows, SimdKernel::kPortable);
  EXPECT_LT(cv::norm(fast_rows, portable_rows, cv::NORM_INF), 1e-4);
  EXPECT_LT(cv::norm(fast_rows.row(4), fast.row(1), cv::NORM_INF), 1e-6);
  // One sample against bilinear interpolation written out.
  const double x = -1.5 + 1.17 * 10 + 0.05 * 4, y = -0.7 + 1.41 * 4 - 0.03 * 10;
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double fx = x - x0, fy = y - y0;
  const double expected = (1 - fx) * (1 - fy) * source(y0, x0) + fx * (1 - fy) * source(y0, x0 + 1) +
                          (1 - fx) * fy * source(y0 + 1, x0) + fx * fy * source(y0 + 1, x0 + 1);
  EXPECT_NEAR(fast(4, 10), expected, 1e-4);
}

}  // namespace
}  // namespace oefmt
