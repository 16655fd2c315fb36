// SPDX-License-Identifier: GPL-3.0-or-later
// Constants of the spectral tables (doc/method.md, The frame's spectra) and the FFT wrapper.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <limits>

#include "oefmt/error.h"
#include "oefmt/registration/fft.h"
#include "oefmt/registration/phase_correlation.h"
#include "oefmt/registration/spectra.h"
#include "oefmt/registration/warp.h"
#include "support/fixtures.h"

namespace oefmt {
namespace {

TEST(Spectra, LogPolarBaseSpansTheConfiguredRadius) {
  const SpectralContext& context = *test::sharedContext(512);
  EXPECT_NEAR(std::pow(context.logPolarBase(), 512), 0.55 * 512, 1e-6);
  EXPECT_NEAR(std::log(context.logPolarBase()), 0.011017, 2e-6);
  EXPECT_DOUBLE_EQ(context.polarRadiusStep(), 0.75);
}

TEST(Spectra, HighPassIsZeroAtDcAndRisesOutwards) {
  const SpectralContext& context = *test::sharedContext(512);
  const cv::Mat1f& h = context.highPass();
  EXPECT_NEAR(h(256, 256), 0.0f, 1e-7);
  EXPECT_NEAR(h(256, 0), 1.0f, 1e-6);     // radius pi/2 on the axis
  EXPECT_NEAR(h(0, 0), std::pow(std::sin(CV_PI / std::sqrt(2.0)), 2), 1e-5);  // corner ~0.63
  EXPECT_LT(h(256, 250), h(256, 200));
}

TEST(Spectra, WindowIsOneInsideAndZeroAtTheBorder) {
  const SpectralContext& context = *test::sharedContext(512);
  const SeparableWindow& w = context.window();
  const int taper = static_cast<int>(std::floor(0.12 * 512));
  EXPECT_EQ(taper, 61);
  EXPECT_FLOAT_EQ(w(0, 0), 0.0f);
  EXPECT_FLOAT_EQ(w(511, 300), 0.0f);
  EXPECT_FLOAT_EQ(w(taper, taper), 1.0f);
  EXPECT_FLOAT_EQ(w(256, 256), 1.0f);
  for (int i = 0; i < 512; ++i) EXPECT_FLOAT_EQ(w.taper()[i], w.taper()[511 - i]);  // symmetric
  EXPECT_GT(w(30, 256), 0.0f);
  EXPECT_LT(w(30, 256), 1.0f);
}

TEST(Fft, InverseOfForwardReturnsTheImageTimesNSquared) {
  const Fft2d fft(64, FftPlanning::kEstimate);
  cv::Mat1f image(64, 64), back;
  cv::randu(image, 0.0f, 1.0f);
  cv::Mat2f spectrum;
  fft.forward(image, spectrum);
  EXPECT_EQ(spectrum.cols, 33);
  fft.inverse(spectrum, back);
  EXPECT_LT(cv::norm(back / (64.0f * 64.0f), image, cv::NORM_INF), 1e-5);
}

// The in-place transforms (image in the padded rows of the spectrum's buffer) give the same
// spectrum and image as the out-of-place ones.
TEST(Fft, InPlaceTransformsMatchOutOfPlace) {
  const Fft2d fft(64, FftPlanning::kMeasure);
  cv::Mat1f image(64, 64);
  cv::randu(image, -1.0f, 1.0f);
  cv::Mat2f expected;
  fft.forward(image, expected);

  cv::Mat2f buffer;
  cv::Mat1f view = fft.inPlaceInput(buffer);
  ASSERT_EQ(view.data, buffer.data);
  image.copyTo(view);
  fft.forwardInPlace(buffer);
  EXPECT_LT(cv::norm(buffer, expected, cv::NORM_INF), 1e-4 * cv::norm(expected, cv::NORM_INF));

  fft.inverseInPlace(buffer);
  EXPECT_LT(cv::norm(fft.realView(buffer) / (64.0f * 64.0f), image, cv::NORM_INF), 1e-5);
  cv::Mat2f wrong(64, 32);
  EXPECT_THROW(fft.forwardInPlace(wrong), InputError);
}

// The fftshift folded into the spectrum must give exactly the shifted, scaled surface, and the
// one-pass peak search the same peak and sums as separate passes (cv::minMaxLoc, cv::norm).
TEST(PhaseCorrelation, CentredCrossPowerEqualsShiftingTheSurface) {
  for (const bool half_turn : {false, true}) {
    const int n = 64;
    const Fft2d fft(n, FftPlanning::kEstimate);
    cv::Mat1f a(n, n), b(n, n);
    cv::randu(a, 0.0f, 1.0f);
    cv::randu(b, 0.0f, 1.0f);
    cv::Mat2f fa, fb, cross, centred_cross;
    fft.forward(a, fa);
    fft.forward(b, fb);
    normalisedCrossPower(fa, fb, cross, half_turn);
    cv::Mat1f correlation, direct;
    fft.inverse(cross, correlation);
    // The reference: fftshift (a half-size cyclic shift of rows and columns) and 1/N^2.
    cv::Mat1f shifted(n, n);
    for (int r = 0; r < n; ++r) {
      for (int c = 0; c < n; ++c) shifted(r, c) = correlation((r + n / 2) % n, (c + n / 2) % n) / (n * n);
    }
    SurfaceStats expected_stats;
    expected_stats.abs_sum = cv::norm(shifted, cv::NORM_L1);
    expected_stats.square_sum = cv::norm(shifted, cv::NORM_L2SQR);
    centredCrossPower(fa, fb, centred_cross, half_turn);
    fft.inverse(centred_cross, direct);
    EXPECT_LT(cv::norm(direct, shifted, cv::NORM_INF), 1e-6);

    SurfaceStats stats;
    const SurfacePeak with_stats = findPeak(direct, true, &stats);
    double low = 0.0, high = 0.0;
    cv::Point low_at, high_at;
    cv::minMaxLoc(shifted, &low, &high, &low_at, &high_at);
    const cv::Point largest = -low > high ? low_at : high_at;
    EXPECT_EQ(with_stats.row, largest.y);
    EXPECT_EQ(with_stats.col, largest.x);
    EXPECT_NEAR(stats.abs_sum, expected_stats.abs_sum, 1e-4 * expected_stats.abs_sum);
    EXPECT_NEAR(stats.square_sum, expected_stats.square_sum, 1e-4 * expected_stats.square_sum);
  }
}

TEST(PhaseCorrelation, OnePassPeakFindsNegativePeaksAndTheFirstOfTies) {
  cv::Mat1f surface = cv::Mat1f::zeros(8, 8);
  surface(2, 3) = 0.5f;
  surface(5, 1) = -0.9f;
  SurfaceStats stats;
  SurfacePeak peak = findPeak(surface, true, &stats);
  EXPECT_EQ(peak.row, 5);
  EXPECT_EQ(peak.col, 1);
  EXPECT_FLOAT_EQ(peak.value, 0.9f);
  EXPECT_NEAR(stats.abs_sum, 1.4, 1e-6);
  surface(5, 1) = 0.5f;  // a tie: row-major first, as cv::minMaxLoc
  peak = findPeak(surface, true, &stats);
  EXPECT_EQ(peak.row, 2);
  EXPECT_EQ(peak.col, 3);
}

TEST(PhaseCorrelation, AWindowPastTheLastUnwrappedColumnReportsNoPeakAtThatColumn) {
  // A polar unwrap's columns do not wrap: a window centred beyond them (a shift longer than the
  // unwrap reaches) holds nothing, and its empty result must not land on a column of another
  // radius.
  cv::Mat1f surface = cv::Mat1f::zeros(9, 64);
  surface(4, 36) = 1.0f;  // at the column a centre of 100 would wrap onto
  const SurfacePeak beyond = findPeakInWindow(surface, cv::Point(100, 4), 2, 2, false);
  EXPECT_EQ(beyond.value, 0.0f);
  EXPECT_EQ(beyond.row, 4);
  EXPECT_EQ(beyond.col, 63);
  const SurfacePeak before = findPeakInWindow(surface, cv::Point(-7, 4), 2, 2, false);
  EXPECT_EQ(before.value, 0.0f);
  EXPECT_EQ(before.col, 0);
  // Cyclic columns still wrap.
  EXPECT_FLOAT_EQ(findPeakInWindow(surface, cv::Point(100, 4), 2, 2, true).value, 1.0f);
}

// A sinc peak widened by a Gaussian blur of `sigma` bins (as resampling widens the log-polar
// correlation peak), centred at (row, col) + offset on both axes.
cv::Mat1f widenedPeakSurface(int row, int col, double offset, double sigma) {
  auto profile = [sigma](double x) {
    double sum = 0.0, weights = 0.0;
    for (double u = -6.0 * sigma; u <= 6.0 * sigma; u += 0.01) {
      const double w = std::exp(-0.5 * u * u / (sigma * sigma));
      const double t = CV_PI * (x - u);
      sum += w * (std::fabs(t) < 1e-12 ? 1.0 : std::sin(t) / t);
      weights += w;
    }
    return sum / weights;
  };
  cv::Mat1f surface(16, 16);
  for (int r = 0; r < surface.rows; ++r) {
    for (int c = 0; c < surface.cols; ++c) {
      surface(r, c) = static_cast<float>(profile(r - row - offset) * profile(c - col - offset));
    }
  }
  return surface;
}

// At whole-bin offsets both neighbours of a widened peak are alike, and the larger-neighbour
// ratio jumps from one side to the other (here by ~0.5 bin between offsets -0.05 and +0.05);
// the widened-peak refinement follows the offset continuously.
TEST(PhaseCorrelation, WidenedPeakRefinementIsContinuousAtWholeBins) {
  for (double sigma : {0.4, 0.6}) {
    double previous = -1.0;
    for (double offset = -0.3; offset <= 0.301; offset += 0.05) {
      const cv::Mat1f surface = widenedPeakSurface(8, 7, offset, sigma);
      const SurfacePeak peak = findPeak(surface, true, nullptr, PeakShape::kBroadened);
      ASSERT_EQ(peak.row, 8);
      ASSERT_EQ(peak.col, 7);
      EXPECT_NEAR(peak.sub_row - 8, offset, 0.09) << "sigma " << sigma;
      EXPECT_NEAR(peak.sub_col - 7, offset, 0.09) << "sigma " << sigma;
      EXPECT_GT(peak.sub_col, previous) << "not monotonic at offset " << offset;
      previous = peak.sub_col;
    }
  }
  const SurfacePeak ratio = findPeak(widenedPeakSurface(8, 7, 0.0, 0.6), true, nullptr,
                                     PeakShape::kDirichlet);
  EXPECT_GT(std::fabs(ratio.sub_col - 7), 0.15) << "the ratio's jump this refinement avoids";
}

// An ideal shift: the Dirichlet refinement is exact, and the widened-peak one stays close.
TEST(PhaseCorrelation, PeakRefinementsOnAnIdealSincPeak) {
  for (double offset : {-0.4, -0.2, 0.1, 0.3}) {
    const cv::Mat1f surface = widenedPeakSurface(8, 7, offset, 1e-3);
    EXPECT_NEAR(findPeak(surface, true).sub_col - 7, offset, 0.01);
    EXPECT_NEAR(findPeak(surface, true, nullptr, PeakShape::kBroadened).sub_col - 7, offset, 0.03);
  }
}

// The CPU-specific kernel (AVX2 + FMA where the CPU has it) and the portable one agree up to
// float rounding, including the border blocks that fall back to scalar samples. (On a CPU
// without AVX2 both are the portable kernel and the test checks nothing more.)
TEST(Warp, FastKernelMatchesThePortableOne) {
  const int n = 128;
  const SeparableWindow window(n, 0.1);
  cv::Mat1f source(n, n);
  cv::randu(source, 0.0f, 255.0f);
  for (const double rotation : {0.0, 0.3, -2.0, 3.1}) {
    for (const double zoom : {1.0, 0.8, 1.3}) {
      cv::Mat1f fast, portable;
      warpSimilarityWindowed(source, rotation, zoom, window, fast, 100.0f, SimdKernel::kAuto);
      warpSimilarityWindowed(source, rotation, zoom, window, portable, 100.0f, SimdKernel::kPortable);
      // FMA rounds the sample position once instead of twice: ~1e-5 px, times the up to
      // 255-per-pixel slopes of this noise texture.
      EXPECT_LT(cv::norm(fast, portable, cv::NORM_INF), 1e-2) << rotation << " " << zoom;
      EXPECT_GT(cv::norm(portable, cv::NORM_INF), 10.0);
    }
  }
}

// A registration gone wrong can hand the warp a NaN rotation or an absurd zoom: the output is
// finite (zero where the source is not sampled), with either kernel, and no position is cast
// to int out of range (the ASan + UBSan build runs this too).
TEST(Warp, NonFiniteOrExtremeTransformsGiveFiniteOutput) {
  const int n = 64;
  const SeparableWindow window(n, 0.1);
  cv::Mat1f source(n, n);
  cv::randu(source, 1.0f, 255.0f);
  for (const SimdKernel kernel : {SimdKernel::kAuto, SimdKernel::kPortable}) {
    cv::Mat1f out;
    warpSimilarityWindowed(source, std::numeric_limits<double>::quiet_NaN(), 1.0, window, out,
                           0.0f, kernel);
    EXPECT_EQ(cv::countNonZero(out), 0);
    for (const double zoom : {1e-30, 1e-45, 1e30}) {
      warpSimilarityWindowed(source, 0.3, zoom, window, out, 0.0f, kernel);
      EXPECT_TRUE(cv::checkRange(out)) << zoom;
    }
  }
}

TEST(Warp, HalfTurnMapsPixelsOntoTheirMirrorAboutTheImageCentre) {
  const SeparableWindow flat(64, 0.0);  // no taper: compare raw pixels
  cv::Mat1f image(64, 64, 0.0f), turned;
  image(10, 20) = 1.0f;
  warpSimilarityWindowed(image, CV_PI, 1.0, flat, turned);
  EXPECT_NEAR(turned(63 - 10, 63 - 20), 1.0f, 1e-4);  // x -> N - 1 - x about ((N-1)/2, (N-1)/2)
  EXPECT_NEAR(cv::sum(turned)[0], 1.0, 1e-4);
}

}  // namespace
}  // namespace oefmt

namespace oefmt {
namespace {

// oefmt_offline analyses frames on several threads, each with its own builder: a frame's
// spectra must not depend on what its builder analysed before.
TEST(Spectra, NoisePowerOfWhiteNoiseIsItsMeanPowerPerFrequency) {
  // The spectrum of white noise of std s over an N x N image: E|F|^2 = N^2 s^2 everywhere.
  const int n = 256;
  const Fft2d fft(n, FftPlanning::kEstimate);
  for (const double sigma : {0.02, 0.2}) {
    cv::Mat1f noise(n, n);
    cv::RNG(11).fill(noise, cv::RNG::NORMAL, 0.0, sigma);
    cv::Mat2f spectrum;
    fft.forward(noise, spectrum);
    // A quartile of a few thousand exponential values: within about 5 % (one sigma).
    EXPECT_NEAR(noisePower(spectrum) / (n * n * sigma * sigma), 1.0, 0.15) << sigma;
  }
  // A smooth image has (almost) no power out there.
  cv::Mat1f smooth(n, n);
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) smooth(r, c) = static_cast<float>(std::sin(0.05 * c) * std::cos(0.03 * r));
  }
  cv::Mat2f spectrum;
  fft.forward(smooth, spectrum);
  EXPECT_LT(noisePower(spectrum), 1e-3 * n * n * 0.02 * 0.02);
}

TEST(Spectra, TheRefinementImageKnowsTheFramesSensorNoise) {
  // A textured frame under white noise of std s: the refinement image carries s^2 (from the
  // spectrum's noise power over the apodization's energy), which its steps take out of the
  // gradients (refineSimilarity). The test texture's own fine detail reads as about 0.02^2 more.
  const auto context = test::sharedContext(256);
  SpectraBuilder builder(context);
  const auto pair = test::warpedPair(sim::ViewMotion{}, 256, 5);
  for (const double sigma : {0.05, 0.1}) {
    cv::Mat1f noisy = pair.older.clone(), noise(noisy.size());
    cv::RNG(17).fill(noise, cv::RNG::NORMAL, 0.0, sigma);
    noisy += noise;
    const FrameSpectra frame = builder.build(noisy);
    EXPECT_NEAR(frame.refinement.noise_variance / (sigma * sigma), 1.0, 0.25) << sigma;
  }
}

TEST(Spectra, AFramesSpectraDoNotDependOnTheBuildersHistory) {
  const auto first = test::warpedPair(sim::ViewMotion{}, 128, 5);
  const auto second = test::warpedPair(sim::ViewMotion{}, 128, 9);
  const auto context = test::sharedContext(128);
  SpectraBuilder fresh(context), used(context);
  used.build(first.older);
  const FrameSpectra a = fresh.build(second.older), b = used.build(second.older);
  const auto same = [](const cv::Mat& x, const cv::Mat& y) {
    return x.size() == y.size() && x.type() == y.type() &&
           std::memcmp(x.data, y.data, x.total() * x.elemSize()) == 0;
  };
  EXPECT_TRUE(same(a.grey, b.grey));
  EXPECT_TRUE(same(a.spectrum, b.spectrum));
  EXPECT_TRUE(same(a.log_polar_spectrum, b.log_polar_spectrum));
}

TEST(Spectra, ThePreparedImagesStatisticsAreTheImagesOwn) {
  // prepareImage hands the spectra the mean and the largest |value| of its one pass; an image
  // prepared elsewhere (unknown: NaN) gets them computed: the same spectra either way.
  cv::Mat1f image(128, 128);
  cv::RNG(3).fill(image, cv::RNG::UNIFORM, -0.2, 0.9);
  image(70, 33) = -1.5f;  // the largest |value| is negative
  const PreparedImage prepared = prepareImage(image, 128);
  double low = 0.0, high = 0.0;
  cv::minMaxLoc(prepared.grey, &low, &high);
  EXPECT_EQ(prepared.largest_magnitude, 1.5);
  EXPECT_EQ(prepared.largest_magnitude, std::max(-low, high));
  EXPECT_NEAR(prepared.mean, cv::mean(prepared.grey)[0], 1e-7);  // float row sums

  PreparedImage unknown = prepared;
  unknown.mean = unknown.largest_magnitude = std::numeric_limits<double>::quiet_NaN();
  SpectraBuilder builder(test::sharedContext(128));
  const FrameSpectra known_stats = builder.build(prepared), computed = builder.build(unknown);
  EXPECT_NEAR(known_stats.mean, computed.mean, 1e-7);
  EXPECT_LT(cv::norm(known_stats.spectrum, computed.spectrum, cv::NORM_INF),
            1e-5 * cv::norm(computed.spectrum, cv::NORM_INF));

  // A float frame far brighter than the spectra take is scaled down, and its mean with it.
  const PreparedImage bright = prepareImage(cv::Mat1f(image * 1e6f), 128);
  EXPECT_NEAR(bright.largest_magnitude, 1.5e6, 1.0);
  const FrameSpectra scaled = builder.build(bright);
  EXPECT_NEAR(scaled.mean, computed.mean * 1024.0 / 1.5, 1e-4);
}

TEST(SeparableWindow, OverlapShareIsTheWindowedEnergyTwoShiftedFramesShare) {
  const int n = 64;
  const SeparableWindow window(n, 0.1);
  EXPECT_DOUBLE_EQ(window.overlapShare({0.0, 0.0}), 1.0);
  // Separable, symmetric and falling with the shift along either axis.
  double brute = 0.0, whole = 0.0;
  for (int i = 0; i < n; ++i) {
    whole += double(window.taper()[i]) * window.taper()[i];
    if (i + 10 < n) brute += double(window.taper()[i]) * window.taper()[i + 10];
  }
  EXPECT_NEAR(window.overlapShare({10.0, 0.0}), brute / whole, 1e-12);
  EXPECT_DOUBLE_EQ(window.overlapShare({-10.0, 0.0}), window.overlapShare({10.0, 0.0}));
  EXPECT_NEAR(window.overlapShare({10.0, 10.0}), (brute / whole) * (brute / whole), 1e-12);
  EXPECT_LT(window.overlapShare({20.0, 0.0}), window.overlapShare({10.0, 0.0}));
  EXPECT_GT(window.overlapShare({1000.0, 0.0}), 0.0) << "beyond the frame: bounded away from 0";
}

}  // namespace
}  // namespace oefmt
