// SPDX-License-Identifier: GPL-3.0-or-later
// Pattern matching of energy vectors (doc/method.md, Pattern matching): identity, known
// stretches and shifts, swapped inputs, rendered pairs.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "oefmt/registration/pattern_matching.h"
#include "oefmt/sim/texture.h"
#include "support/fixtures.h"

namespace oefmt {
namespace {

constexpr int kN = 512;

struct Peak {
  double bin, width, height;
};

// A translation-energy-like vector: Gaussian peaks (one per depth layer) on a faint floor.
std::vector<float> peaks(const std::vector<Peak>& list, int n = kN) {
  std::vector<float> v(n, 0.0f);
  for (int j = 0; j < n; ++j) {
    double x = 1e-5;
    for (const Peak& p : list) x += p.height * std::exp(-0.5 * std::pow((j - p.bin) / p.width, 2));
    v[j] = static_cast<float>(x);
  }
  return v;
}

// Two layers at bins 13 and 26 (shifts 10 and 20 px); the correlation peak width does not grow
// with the shift, so the stretched vector keeps its peak widths.
std::vector<float> twoLayers(double factor) {
  return peaks({{13.3 * factor, 1.4, 0.4}, {26.6 * factor, 1.4, 1.0}});
}

StretchMatchOptions stretchOptions(double init, double key) {
  StretchMatchOptions options;
  options.init = init;
  options.key = key;
  return options;
}

TEST(StretchMatch, IdentityReturnsOne) {
  const MatchResult r = matchStretch(twoLayers(1.0), twoLayers(1.0), stretchOptions(1.0, 16));
  ASSERT_TRUE(r.valid);
  EXPECT_NEAR(r.value, 1.0, 0.002);  // REF: 0.9685
  EXPECT_TRUE(std::isfinite(r.sigma));
  EXPECT_GT(r.sigma, 0.0);
}

class StretchFactor : public ::testing::TestWithParam<double> {};

TEST_P(StretchFactor, WithinOneGridStep) {
  const double factor = GetParam();
  const double key = factor > 1.7 ? 13.0 : 16.0;
  const double grid_step = std::exp(key / 1000.0) - 1.0;
  const MatchResult r =
      matchStretch(twoLayers(1.0), twoLayers(factor), stretchOptions(std::round(factor), key));
  ASSERT_TRUE(r.valid);
  EXPECT_NEAR(r.value / factor, 1.0, grid_step);  // REF: 1.94 for 2, 1.45 for 1.5
  EXPECT_NEAR(r.value / factor, 1.0, 0.006) << "parabolic refinement should beat the grid";
  EXPECT_LT(r.sigma, 0.05);
}

INSTANTIATE_TEST_SUITE_P(Factors, StretchFactor, ::testing::Values(0.8, 1.0, 1.12, 1.5, 2.0));

TEST(StretchMatch, SwappedInputsGiveTheReciprocal) {
  for (double factor : {1.0, 1.3, 1.5, 2.0}) {
    const MatchResult forward = matchStretch(twoLayers(1.0), twoLayers(factor), stretchOptions(-1, 16));
    const MatchResult backward = matchStretch(twoLayers(factor), twoLayers(1.0), stretchOptions(-1, 16));
    ASSERT_TRUE(forward.valid && backward.valid) << factor;
    EXPECT_NEAR(forward.value * backward.value, 1.0, 0.01) << factor;
  }
}

TEST(StretchMatch, InitWindowRejectsTheLayerAlias) {
  // b is a at 2x: stretching a by 2 matches; so (partly) does moving the 13-bin layer onto 26.
  const MatchResult r = matchStretch(twoLayers(1.0), twoLayers(2.0), stretchOptions(2.0, 13));
  ASSERT_TRUE(r.valid);
  EXPECT_NEAR(r.value, 2.0, 0.02);
}

TEST(StretchMatch, DegenerateInputsAreInvalidButFinite) {
  const std::vector<float> zeros(kN, 0.0f);
  std::vector<float> nans(kN, std::numeric_limits<float>::quiet_NaN());
  const std::vector<float> v = twoLayers(1.0);
  for (const auto& pair : {std::make_pair(zeros, v), std::make_pair(v, zeros),
                           std::make_pair(nans, v), std::make_pair(std::vector<float>{}, v)}) {
    const MatchResult r = matchStretch(pair.first, pair.second, stretchOptions(1.0, 16));
    EXPECT_FALSE(r.valid);
    EXPECT_TRUE(std::isfinite(r.value) && std::isfinite(r.sigma));
    EXPECT_DOUBLE_EQ(r.value, 1.0);
  }
}

TEST(StretchMatch, NoQualifyingMinimumReportsThePriorNotTheSmallestFactor) {
  // b's only layer is 3.5x away: nothing within the init window.
  const MatchResult r = matchStretch(peaks({{10, 1.4, 1.0}}), peaks({{35, 1.4, 1.0}}),
                                     stretchOptions(1.0, 16));
  EXPECT_FALSE(r.valid);
  EXPECT_DOUBLE_EQ(r.value, 1.0);  // REF returns about exp(-1.6)
}

// A zoom-energy-like vector: one peak near N/2, shifted by `shift` bins.
std::vector<float> zoomVector(double shift) {
  return peaks({{kN / 2.0 + shift, 1.3, 1.0}, {kN / 2.0 + 9.0 + shift, 2.0, 0.15}});
}

class ShiftBins : public ::testing::TestWithParam<double> {};

TEST_P(ShiftBins, WithinOneStep) {
  const double shift = GetParam();
  const MatchResult r = matchShift(zoomVector(0.0), zoomVector(shift), ShiftMatchOptions{});
  ASSERT_TRUE(r.valid);
  EXPECT_NEAR(r.value, shift, 0.04);  // REF: shift - 1, fractions mirrored
  EXPECT_TRUE(std::isfinite(r.sigma));  // REF: NaN
  EXPECT_GT(r.sigma, 0.0);
}

INSTANTIATE_TEST_SUITE_P(Shifts, ShiftBins,
                         ::testing::Values(0.0, 0.3, -0.7, 1.0, 2.37, -5.5, 12.25, -20.8));

TEST(ShiftMatch, SwappedInputsNegate) {
  const MatchResult forward = matchShift(zoomVector(0.0), zoomVector(3.6), ShiftMatchOptions{});
  const MatchResult backward = matchShift(zoomVector(3.6), zoomVector(0.0), ShiftMatchOptions{});
  ASSERT_TRUE(forward.valid && backward.valid);
  EXPECT_NEAR(forward.value, -backward.value, 0.02);
}

TEST(ShiftMatch, DegenerateInputsAreInvalidButFinite) {
  const std::vector<float> zeros(kN, 0.0f);
  const MatchResult r = matchShift(zeros, zoomVector(0.0), ShiftMatchOptions{});
  EXPECT_FALSE(r.valid);
  EXPECT_TRUE(std::isfinite(r.value) && std::isfinite(r.sigma));
}

TEST(PeakNear, FindsTheLayerNearestThePrediction) {
  const std::vector<float> v = twoLayers(1.0);
  const auto near_far = peakNear(v, 25.0, 3.0, 0.05);
  ASSERT_TRUE(near_far.has_value());
  EXPECT_NEAR(*near_far, 26.6, 0.05);
  const auto near_low = peakNear(v, 14.0, 3.0, 0.05);
  ASSERT_TRUE(near_low.has_value());
  EXPECT_NEAR(*near_low, 13.3, 0.05);
  EXPECT_FALSE(peakNear(v, 40.0, 3.0, 0.05).has_value());
  EXPECT_NEAR(refinedArgmax(v), 26.6, 0.05);
}

TEST(EnergyPeaks, ListsTheLayersHighestFirst) {
  const std::vector<EnergyPeak> both = energyPeaks(twoLayers(1.0), 0.05);
  ASSERT_EQ(both.size(), 2u);
  EXPECT_NEAR(both[0].bin, 26.6, 0.05);  // the higher one first
  EXPECT_NEAR(both[1].bin, 13.3, 0.05);
  EXPECT_GT(both[0].height, both[1].height);
  const std::vector<EnergyPeak> high = energyPeaks(twoLayers(1.0), 0.5);  // the 0.4 layer drops
  ASSERT_EQ(high.size(), 1u);
  EXPECT_NEAR(high[0].bin, 26.6, 0.05);
  EXPECT_TRUE(energyPeaks(std::vector<float>(kN, 0.0f), 0.05).empty());
  EXPECT_TRUE(energyPeaks({1.0f, 0.5f}, 0.05).empty());
}

// Rendered images: two planes moving 10 and 20 px, then 15 and 30 px.
TEST(StretchMatch, RenderedTwoPlanePairsAtOneAndAHalfTimesTheSpeed) {
  const cv::Mat1f ground = sim::proceduralTexture({2048, 2048}, 11, sim::TextureStyle::kCells, 40);
  const cv::Mat1f roofs = sim::proceduralTexture({2048, 2048}, 12, sim::TextureStyle::kCells, 40);
  const cv::Mat1f mask = sim::blockMask({2048, 2048}, 13, 96.0, 0.7);
  const cv::Point2d centre(1024, 1024);
  const cv::Point2d unit(std::cos(0.6), std::sin(0.6));
  const auto view = [&](double ground_px, double roof_px) {
    return sim::renderTwoLayerView(ground, roofs, mask, centre, unit * ground_px, unit * roof_px, kN);
  };
  const cv::Mat1f v0 = view(0, 0), v1 = view(10, 20), v2 = view(25, 50);
  const PairRegistration r01 = test::registerImages(v0, v1);
  const PairRegistration r12 = test::registerImages(v1, v2);
  const PairRegistration r02 = test::registerImages(v0, v2);
  const MatchResult pmt12 = matchStretch(r01.translation_energy, r12.translation_energy,
                                         stretchOptions(1.0, 16));
  const MatchResult pmt02 = matchStretch(r01.translation_energy, r02.translation_energy,
                                         stretchOptions(2.0, 13));
  ASSERT_TRUE(pmt12.valid);
  ASSERT_TRUE(pmt02.valid);
  EXPECT_NEAR(pmt12.value, 1.5, 0.03);
  EXPECT_NEAR(pmt02.value, 2.5, 0.05);
}

// PMS on rendered zooms: S of a 1.04 zoom against S of a 1.10 zoom.
TEST(ShiftMatch, RenderedZoomPairs) {
  sim::ViewMotion small_zoom, large_zoom;
  small_zoom.zoom = 1.04;
  large_zoom.zoom = 1.10;
  const auto a = test::warpedPair(small_zoom);
  const auto b = test::warpedPair(large_zoom);
  const PairRegistration ra = test::registerImages(a.older, a.newer);
  const PairRegistration rb = test::registerImages(b.older, b.newer);
  Registrar registrar(test::sharedContext(kN));
  const MatchResult r = matchShift(ra.zoom_energy, rb.zoom_energy, ShiftMatchOptions{});
  ASSERT_TRUE(r.valid);
  // b's zoom is larger: its peak sits at lower bins (ln s = -(j - N/2) ln b).
  const double expected = -(std::log(1.10) - std::log(1.04)) / registrar.logZoomPerBin();
  EXPECT_NEAR(r.value, expected, 0.15);
}

}  // namespace
}  // namespace oefmt
