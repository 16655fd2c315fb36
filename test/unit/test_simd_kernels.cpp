// SPDX-License-Identifier: GPL-3.0-or-later
// The CPU-specific kernels (AVX2 + FMA where the CPU has both) against the portable code: the
// same results up to float rounding, for row lengths that leave a scalar tail, and the same
// handling of vanished values. (On a CPU without AVX2 both sides are the portable code.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <string>
#include <utility>
#include <vector>

#if defined(__x86_64__)
#include <cpuid.h>
#endif

#include "oefmt/registration/fft.h"
#include "oefmt/registration/phase_correlation.h"
#include "oefmt/registration/registration_config.h"
#include "oefmt/error.h"
#include "oefmt/registration/spectra.h"
#include "registration/simd_kernels.h"

namespace oefmt {
namespace {

cv::Mat2f randomSpectrum(int rows, int cols, int seed) {
  cv::Mat2f spectrum(rows, cols);
  cv::RNG rng(seed);
  rng.fill(spectrum, cv::RNG::NORMAL, 0.0, 50.0);
  return spectrum;
}

// The configuration of an N = `size` context whose FFT plans are estimated, not measured: the
// kernels under test do not depend on them.
RegistrationConfig estimatedConfig(int size) {
  RegistrationConfig config;
  config.size = size;
  config.fft_planning = FftPlanning::kEstimate;
  return config;
}

TEST(SimdKernels, CrossPowerMatchesThePortableLoop) {
  // 45 complex columns (the real FFT's N/2 + 1 at N = 88): eight-wide steps, a four-wide one
  // and a tail of one.
  const cv::Mat2f newer = randomSpectrum(16, 45, 1);
  cv::Mat2f older = randomSpectrum(16, 45, 2);
  older(3, 5) = cv::Vec2f(0.0f, 0.0f);    // a vanished product gives 0, not NaN
  older(4, 42) = cv::Vec2f(0.0f, 0.0f);   // also in the four-wide step
  older(4, 44) = cv::Vec2f(0.0f, 0.0f);   // and in the tail
  for (const bool half_turn : {false, true}) {
    cv::Mat2f fast, portable, fast_centred, portable_centred;
    normalisedCrossPower(newer, older, fast, half_turn, SimdKernel::kAuto);
    normalisedCrossPower(newer, older, portable, half_turn, SimdKernel::kPortable);
    centredCrossPower(newer, older, fast_centred, half_turn, SimdKernel::kAuto);
    centredCrossPower(newer, older, portable_centred, half_turn, SimdKernel::kPortable);
    EXPECT_LT(cv::norm(fast, portable, cv::NORM_INF), 1e-6);
    EXPECT_LT(cv::norm(fast_centred, portable_centred, cv::NORM_INF), 1e-6 / (16.0 * 16.0));
    EXPECT_EQ(fast(3, 5), cv::Vec2f(0.0f, 0.0f));
    EXPECT_EQ(fast(4, 42), cv::Vec2f(0.0f, 0.0f));
    EXPECT_EQ(fast(4, 44), cv::Vec2f(0.0f, 0.0f));
    EXPECT_NEAR(std::hypot(fast(7, 9)[0], fast(7, 9)[1]), 1.0, 1e-6);
    // The centring sign alternates with the column (and the row).
    EXPECT_NEAR(fast_centred(2, 1)[0], -fast(2, 1)[0] / (16.0 * 16.0), 1e-9);
    EXPECT_NEAR(fast_centred(3, 1)[0], fast(3, 1)[0] / (16.0 * 16.0), 1e-9);
  }
}

TEST(SimdKernels, NoiseWeightedCrossPowerMatchesThePortableLoop) {
  // 45 complex columns: four-wide steps and a tail of one; noise powers around the values'
  // |.|^2 (50^2 per component), so that some weights clip at 0 and others do not.
  const cv::Mat2f newer = randomSpectrum(16, 45, 3);
  cv::Mat2f older = randomSpectrum(16, 45, 4);
  older(5, 44) = cv::Vec2f(0.0f, 0.0f);  // weight 0, not NaN
  for (const bool half_turn : {false, true}) {
    cv::Mat2f fast, portable, plain;
    centredCrossPower(newer, older, fast, half_turn, SimdKernel::kAuto, 4000.0f, 6000.0f);
    centredCrossPower(newer, older, portable, half_turn, SimdKernel::kPortable, 4000.0f, 6000.0f);
    centredCrossPower(newer, older, plain, half_turn, SimdKernel::kPortable);
    EXPECT_LT(cv::norm(fast, portable, cv::NORM_INF), 1e-6 / (16.0 * 16.0));
    EXPECT_EQ(fast(5, 44), cv::Vec2f(0.0f, 0.0f));
    int zeroed = 0, kept = 0;
    for (int r = 0; r < 16; ++r) {
      for (int c = 0; c < 45; ++c) {
        // Each value is the unweighted one times its weight in [0, 1].
        const cv::Vec2f p = newer(r, c), q = older(r, c);
        const double wp = std::max(0.0, 1.0 - 4000.0 / (p.dot(p) + 1e-30));
        const double wq = std::max(0.0, 1.0 - 6000.0 / (q.dot(q) + 1e-30));
        EXPECT_NEAR(portable(r, c)[0], plain(r, c)[0] * wp * wq, 1e-7);
        (wp * wq == 0.0 ? zeroed : kept) += 1;
      }
    }
    EXPECT_GT(zeroed, 50);
    EXPECT_GT(kept, 50);
  }
}

TEST(SimdKernels, RowStatisticsMatchThePortableLoop) {
  // 37 floats: four eight-wide steps and a tail of five; negative values for sum vs |sum|.
  cv::Mat1f row(1, 37);
  cv::RNG(8).fill(row, cv::RNG::NORMAL, 0.1, 1.0);
  row(0, 35) = -7.0f;  // the minimum, in the tail
  const detail::RowStats fast = detail::rowStats(row[0], row.cols, detail::runsAvx2(SimdKernel::kAuto));
  const detail::RowStats portable = detail::rowStatsPortable(row[0], row.cols);
  double sum = 0.0, abs_sum = 0.0, square_sum = 0.0;
  for (const float v : row) {
    sum += v;
    abs_sum += std::fabs(v);
    square_sum += double(v) * v;
  }
  for (const detail::RowStats& stats : {fast, portable}) {
    EXPECT_EQ(stats.min, -7.0f);
    EXPECT_EQ(stats.max, *std::max_element(row.begin(), row.end()));
    EXPECT_NEAR(stats.sum, sum, 1e-5 * abs_sum);
    EXPECT_NEAR(stats.abs_sum, abs_sum, 1e-5 * abs_sum);
    EXPECT_NEAR(stats.square_sum, square_sum, 1e-5 * square_sum);
  }
}

TEST(SimdKernels, PeakSearchMatchesThePortableLoop) {
  // 37 columns: four eight-wide steps and a tail of five; the largest |value| negative once.
  cv::Mat1f surface(16, 37);
  cv::RNG(4).fill(surface, cv::RNG::NORMAL, 0.0, 1.0);
  for (const cv::Point at : {cv::Point(36, 9), cv::Point(3, 5)}) {
    cv::Mat1f trial = surface.clone();
    trial(at) = at.x == 3 ? -9.0f : 9.0f;  // in the tail, then a negative one in a step
    SurfaceStats fast_stats, portable_stats;
    const SurfacePeak fast = findPeak(trial, true, &fast_stats, PeakShape::kDirichlet, SimdKernel::kAuto);
    const SurfacePeak portable =
        findPeak(trial, true, &portable_stats, PeakShape::kDirichlet, SimdKernel::kPortable);
    EXPECT_EQ(fast.row, at.y);
    EXPECT_EQ(fast.col, at.x);
    EXPECT_EQ(fast.row, portable.row);
    EXPECT_EQ(fast.col, portable.col);
    EXPECT_EQ(fast.value, portable.value);
    EXPECT_DOUBLE_EQ(fast.sub_row, portable.sub_row);
    EXPECT_DOUBLE_EQ(fast.sub_col, portable.sub_col);
    EXPECT_NEAR(fast_stats.abs_sum, portable_stats.abs_sum, 1e-5 * portable_stats.abs_sum);
    EXPECT_NEAR(fast_stats.square_sum, portable_stats.square_sum, 1e-5 * portable_stats.square_sum);
  }
  // A NaN is never the peak, and the sums carry it.
  cv::Mat1f with_nan = surface.clone();
  with_nan(2, 20) = std::nanf("");
  SurfaceStats fast_stats, portable_stats;
  const SurfacePeak fast = findPeak(with_nan, true, &fast_stats, PeakShape::kDirichlet, SimdKernel::kAuto);
  const SurfacePeak portable =
      findPeak(with_nan, true, &portable_stats, PeakShape::kDirichlet, SimdKernel::kPortable);
  EXPECT_TRUE(std::isfinite(fast.value));
  EXPECT_EQ(fast.value, portable.value);
  EXPECT_TRUE(std::isnan(fast_stats.abs_sum));
  EXPECT_TRUE(std::isnan(portable_stats.square_sum));
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

// Bilinear interpolation written out, 0 outside (the reference for the ray samplers).
double bilinear(const cv::Mat1f& image, double x, double y) {
  const int x0 = static_cast<int>(std::floor(x)), y0 = static_cast<int>(std::floor(y));
  const double fx = x - x0, fy = y - y0;
  auto at = [&](int c, int r) -> double {
    return (c < 0 || r < 0 || c >= image.cols || r >= image.rows) ? 0.0 : image(r, c);
  };
  return (1 - fx) * (1 - fy) * at(x0, y0) + fx * (1 - fy) * at(x0 + 1, y0) +
         (1 - fx) * fy * at(x0, y0 + 1) + fx * fy * at(x0 + 1, y0 + 1);
}

TEST(SimdKernels, LogPolarRaysMatchThePortableLoopAndBilinearSampling) {
  const SpectralContext context(estimatedConfig(68));  // 68 columns: a tail of four after eight-wide steps
  const int n = context.size();
  cv::Mat1f magnitude(n / 2 + 2, n);
  cv::RNG(21).fill(magnitude, cv::RNG::UNIFORM, 0.0f, 10.0f);  // seeded: not the shared RNG
  cv::Mat1f fast, portable;
  context.logPolar(magnitude, fast, SimdKernel::kAuto);
  context.logPolar(magnitude, portable, SimdKernel::kPortable);
  EXPECT_LT(cv::norm(fast, portable, cv::NORM_INF), 1e-4);
  // Row i: angle -pi i / N; column j: radius b^j about (N/2, N/2), outer radii beyond the
  // border (partly zero).
  for (const cv::Point at : {cv::Point(0, 0), cv::Point(5, 17), cv::Point(67, 30), cv::Point(40, 67)}) {
    const double angle = -CV_PI * at.y / n, radius = std::pow(context.logPolarBase(), at.x);
    const double expected = bilinear(magnitude, n / 2 + radius * std::cos(angle),
                                     n / 2 + radius * std::sin(angle));
    EXPECT_NEAR(fast(at.y, at.x), expected, 1e-3) << at;
  }
}

TEST(SimdKernels, PolarRowsMatchThePortableLoopOnAPaddedSurface) {
  const SpectralContext context(estimatedConfig(68));
  const int n = context.size();
  // The registration unwraps a view of an in-place FFT buffer (rows padded).
  cv::Mat2f buffer;
  cv::Mat1f surface = context.fft().inPlaceInput(buffer);
  ASSERT_FALSE(surface.isContinuous());
  cv::RNG(22).fill(surface, cv::RNG::UNIFORM, -1.0f, 1.0f);  // seeded: not the shared RNG
  cv::Mat1f fast, portable;
  context.polarRows(surface, -3, 7, fast, SimdKernel::kAuto);  // rows wrap below 0
  context.polarRows(surface, -3, 7, portable, SimdKernel::kPortable);
  EXPECT_LT(cv::norm(fast, portable, cv::NORM_INF), 1e-5);
  for (const cv::Point at : {cv::Point(0, 0), cv::Point(13, 1), cv::Point(29, 6), cv::Point(55, 4)}) {
    const double direction = 2.0 * CV_PI * (at.y - 3) / n;
    const double radius = context.polarRadiusStep() * at.x;
    const double expected = bilinear(surface, n / 2 + radius * std::cos(direction),
                                     n / 2 + radius * std::sin(direction));
    EXPECT_NEAR(fast(at.y, at.x), expected, 1e-4) << at;
  }
}

#if defined(__x86_64__)
// XINUSE (XGETBV with ECX = 1), bit 2: the upper halves of the vector registers are not in
// their initial state. Where the CPU cannot tell, false.
bool upperHalvesInUse() {
  unsigned eax = 0, ebx = 0, ecx = 0, edx = 0;
  if (!__get_cpuid_count(0xD, 1, &eax, &ebx, &ecx, &edx) || (eax & 4u) == 0) return false;
  unsigned low = 0, high = 0;
  asm volatile("xgetbv" : "=a"(low), "=d"(high) : "c"(1));
  return (low & 4u) != 0;
}
void dirtyUpperHalves() { asm volatile("vpcmpeqd %%ymm15, %%ymm15, %%ymm15" ::: "xmm15"); }
void cleanUpperHalves() { asm volatile("vzeroupper" ::: "memory"); }
#endif

// Every AVX2 kernel returns with the upper halves of the vector registers clean (vzeroupper):
// the portable code that follows uses legacy SSE instructions, and on some CPUs each of those
// waits on dirty upper halves (the scalar refinement ran about twice as slow).
TEST(SimdKernels, KernelsReturnWithTheUpperHalvesOfTheVectorRegistersClean) {
#if defined(__x86_64__)
  if (!detail::runsAvx2(SimdKernel::kAuto)) GTEST_SKIP() << "no AVX2 kernels on this CPU";
  dirtyUpperHalves();
  const bool seen_dirty = upperHalvesInUse();
  cleanUpperHalves();
  if (!seen_dirty || upperHalvesInUse()) GTEST_SKIP() << "the CPU does not report the vector registers' use";
  const SpectralContext context(estimatedConfig(68));  // tails after the eight-wide steps
  const int n = context.size();
  cv::Mat1f magnitude(n / 2 + 2, n), surface(n, n), row(1, 37), out;
  cv::RNG(23).fill(magnitude, cv::RNG::UNIFORM, 0.0f, 10.0f);
  cv::RNG(24).fill(surface, cv::RNG::UNIFORM, -1.0f, 1.0f);
  cv::RNG(25).fill(row, cv::RNG::NORMAL, 0.0f, 1.0f);
  const cv::Mat2f newer = randomSpectrum(n, n / 2 + 1, 5), older = randomSpectrum(n, n / 2 + 1, 6);
  cv::Mat2f cross;
  const std::vector<std::pair<std::string, std::function<void()>>> kernels = {
      {"log-polar rays", [&] { context.logPolar(magnitude, out, SimdKernel::kAuto); }},
      {"polar rows", [&] { context.polarRows(surface, -3, 7, out, SimdKernel::kAuto); }},
      {"row statistics", [&] { detail::rowStats(row[0], row.cols, true); }},
      {"magnitude", [&] { upperHalfMagnitude(newer, cv::Mat1f(n / 2 + 2, n, 1.0f), out, SimdKernel::kAuto); }},
      {"cross power", [&] { normalisedCrossPower(newer, older, cross, false, SimdKernel::kAuto); }},
      {"weighted cross power",
       [&] { centredCrossPower(newer, older, cross, true, SimdKernel::kAuto, 4000.0f, 6000.0f); }},
  };
  for (const auto& kernel : kernels) {
    for (const bool dirty_before : {false, true}) {
      if (dirty_before) {
        dirtyUpperHalves();
      } else {
        cleanUpperHalves();
      }
      kernel.second();
      EXPECT_FALSE(upperHalvesInUse()) << kernel.first << (dirty_before ? ", called dirty" : ", called clean");
    }
  }
#else
  GTEST_SKIP() << "x86-64 only";
#endif
}

// The unwraps refuse a source of the wrong size with a clear error instead of reading past it.
TEST(SimdKernels, UnwrapsRefuseSourcesOfTheWrongSize) {
  const SpectralContext context(estimatedConfig(64));
  cv::Mat1f out;
  for (const SimdKernel kernel : {SimdKernel::kAuto, SimdKernel::kPortable}) {
    EXPECT_THROW(context.logPolar(cv::Mat1f(64, 64, 1.0f), out, kernel), InputError);  // not N/2 + 2 rows
    EXPECT_THROW(context.logPolar(cv::Mat1f(), out, kernel), InputError);
    EXPECT_THROW(context.polarRows(cv::Mat1f(32, 64, 1.0f), 0, 3, out, kernel), InputError);
  }
}

}  // namespace
}  // namespace oefmt
