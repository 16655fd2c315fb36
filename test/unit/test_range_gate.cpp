// SPDX-License-Identifier: GPL-3.0-or-later
// Rangefinder readings against the estimator's altitude: the layers' depth ratios from a
// translation energy vector, the gate that tells the reference plane's readings (and the other
// layers', through their ratios) from outliers, and the initial scale found by the readings'
// vote whichever layer each of them saw.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "oefmt/estimation/range_gate.h"

namespace oefmt {
namespace {

// An energy vector with a peak per layer at shift[l] (bins of 1 px), heights `height[l]`.
std::vector<float> energyWithPeaks(const std::vector<double>& shifts, const std::vector<float>& heights) {
  std::vector<float> energy(200, 0.01f);
  for (std::size_t l = 0; l < shifts.size(); ++l) {
    for (int j = 0; j < 200; ++j) {
      const double d = (j - shifts[l]) / 1.5;
      energy[j] += heights[l] * static_cast<float>(std::exp(-0.5 * d * d));
    }
  }
  return energy;
}

TEST(RangeGate, DepthRatiosComeFromTheEnergyVectorsPeaks) {
  // Ground at depth 10 (shift 50 px), a roof at depth 7.5 (shift 66.7 px); the roof is followed.
  const std::vector<double> ratios = depthRatios(energyWithPeaks({50.0, 200.0 / 3.0}, {1.0f, 0.6f}), 1.0, 200.0 / 3.0);
  ASSERT_EQ(ratios.size(), 2u);
  EXPECT_NEAR(ratios[0], 10.0 / 7.5, 0.01);  // the ground is 4/3 as deep as the roof
  EXPECT_NEAR(ratios[1], 1.0, 0.01);
  // Small bumps are no layers; no vector, no layers.
  EXPECT_EQ(depthRatios(energyWithPeaks({50.0, 120.0}, {1.0f, 0.1f}), 1.0, 50.0).size(), 1u);
  EXPECT_TRUE(depthRatios({}, 1.0, 50.0).empty());
}

TEST(RangeGate, TakesTheReferencePlaneAndOtherLayersThroughTheirRatiosAndRefusesOutliers) {
  RangeGate gate(0.08, 5);
  // Reference plane at 10 m predicted; a reading of 10.3 m is it.
  ASSERT_TRUE(gate.measure(10.3, 10.0).has_value());
  EXPECT_NEAR(*gate.measure(10.3, 10.0), 10.3, 1e-12);
  // A roof 2.5 m up reads 7.5; with the roof's ratio 0.75 in view, it measures the reference as 10.
  const auto roof = gate.measure(7.5, 10.0, {0.75, 1.0});
  ASSERT_TRUE(roof.has_value());
  EXPECT_NEAR(*roof, 10.0, 1e-12);
  // Without that layer in view, the same reading is refused.
  EXPECT_FALSE(gate.measure(7.5, 10.0, {1.0}).has_value());
  EXPECT_FALSE(gate.measure(std::numeric_limits<double>::infinity(), 10.0).has_value());
  EXPECT_FALSE(gate.measure(-1.0, 10.0).has_value());
}

TEST(RangeGate, OpensAgainToReadingsThatConsistentlyDisagree) {
  RangeGate gate(0.08, 5);
  // The estimate drifted 20 % low: five consistent readings, then they are taken again.
  int refused = 0;
  for (int k = 0; k < 5; ++k) refused += gate.measure(12.0 + 0.05 * k, 10.0).has_value() ? 0 : 1;
  EXPECT_EQ(refused, 4);
  // Scattered outliers never open it.
  RangeGate scattered(0.08, 5);
  for (const double r : {13.0, 6.0, 15.0, 5.0, 14.0, 6.5, 16.0}) EXPECT_FALSE(scattered.measure(r, 10.0).has_value());
}

TEST(RangeGate, ScaleVoteFindsWhichLayerTheReadingsSaw) {
  // The estimator's altitude in provisional units of 1 (the roof, its reference, is 7.5 m down);
  // the ground is 10 m down: its depth ratio to the roof is 4/3.
  const std::vector<double> layers = {4.0 / 3.0, 1.0};
  std::vector<RangeObservation> observations;
  for (const double reading : {10.0, 7.5, 10.02, 9.98, 7.52, 10.01}) observations.push_back({reading, 1.0, layers});
  const auto factor = rangeScale(observations);
  ASSERT_TRUE(factor.has_value());
  EXPECT_NEAR(*factor, 7.5, 0.05);  // metres per provisional unit: the roof's depth
  // Readings of the ground alone cannot tell: the ground is taken (the larger depth, smaller factor).
  std::vector<RangeObservation> ground(4, RangeObservation{10.0, 1.0, layers});
  EXPECT_NEAR(*rangeScale(ground), 7.5, 1e-9);
  // A flat scene: one layer, the reading is the reference.
  std::vector<RangeObservation> flat(4, RangeObservation{10.0, 1.0, {1.0}});
  EXPECT_NEAR(*rangeScale(flat), 10.0, 1e-9);
  // Too few readings fit: nothing.
  EXPECT_FALSE(rangeScale({{10.0, 1.0, {}}, {20.0, 1.0, {}}}).has_value());
}

}  // namespace
}  // namespace oefmt
