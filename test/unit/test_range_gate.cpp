// SPDX-License-Identifier: GPL-3.0-or-later
// Rangefinder readings against the estimator's altitude: the layers' depth ratios from a
// translation energy vector, the gate that tells the reference plane's readings (and the other
// layers', through their ratios) from outliers, and the initial scale found by the readings'
// vote whichever layer each of them saw.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "oefmt/estimation/attitude.h"
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

// The vote when the layer below each reading is known (centreDepthRatio): readings of the roofs
// (ratio 0.6 to the followed ground) can no longer pass for the ground's, even when most
// readings see roofs and the energy vectors show the ground alone.
TEST(RangeGate, ScaleVoteTakesTheLayerBelowTheCameraWhereItIsKnown) {
  std::vector<RangeObservation> observations;
  for (const double reading : {12.0, 12.1, 11.9, 20.0, 12.05}) {
    RangeObservation o{reading, 1.0, {1.0}};
    o.centre_ratio = reading < 15.0 ? 0.6 : 1.0;
    observations.push_back(o);
  }
  ASSERT_TRUE(rangeScale(observations).has_value());
  EXPECT_NEAR(*rangeScale(observations), 20.0, 0.2);
  // Without it the roofs, most readings, would win.
  for (RangeObservation& o : observations) o.centre_ratio = 0.0;
  EXPECT_NEAR(*rangeScale(observations), 12.0, 0.2);
  // The gate alike: a roof reading measures the ground's depth through its ratio only.
  RangeGate gate(0.08, 15);
  EXPECT_NEAR(*gate.measure(12.0, 20.0, {}, 0.6), 20.0, 1e-9);
  EXPECT_FALSE(gate.measure(20.0, 20.0, {}, 0.6).has_value());
}

// A smooth random texture of n x n.
cv::Mat1f texture(int n, int seed) {
  cv::Mat1f image(n, n);
  cv::RNG rng(seed);
  rng.fill(image, cv::RNG::UNIFORM, 0.0, 255.0);
  cv::GaussianBlur(image, image, cv::Size(0, 0), 2.0);
  return image;
}

// The newer frame of a pair over the ground moving by `ground` [px], with a roof nearer the camera
// (moving by `roof`) covering a `roof_size` square centred at `roof_centre` of the newer frame.
cv::Mat1f newerFrame(const cv::Mat1f& older, cv::Point2d ground, cv::Point2d roof, cv::Point roof_centre, int roof_size) {
  const int n = older.rows;
  cv::Mat1f newer;
  cv::warpAffine(older, newer, cv::Matx23d(1, 0, ground.x, 0, 1, ground.y), older.size(), cv::INTER_LINEAR,
                 cv::BORDER_REFLECT);
  cv::Mat1f roofs;
  cv::warpAffine(texture(n, 99), roofs, cv::Matx23d(1, 0, roof.x, 0, 1, roof.y), older.size(), cv::INTER_LINEAR,
                 cv::BORDER_REFLECT);
  const cv::Rect square(roof_centre.x - roof_size / 2, roof_centre.y - roof_size / 2, roof_size, roof_size);
  if (roof_size > 0) roofs(square).copyTo(newer(square));
  return newer;
}

TEST(CentreDepthRatio, TellsTheLayerBelowTheReading) {
  const int n = 512;
  cv::Mat1f older = texture(n, 1);
  // The roof's texture is in the older frame too, where the roof was.
  const cv::Point2d ground(30.0, 10.0), roof = ground * (1.0 / 0.625);
  cv::Mat1f roof_texture = texture(n, 99);
  const cv::Rect before(256 - 100 - static_cast<int>(std::lround(roof.x)), 256 - 100 - static_cast<int>(std::lround(roof.y)),
                        200, 200);
  roof_texture(before).copyTo(older(before));
  const cv::Mat1f newer = newerFrame(older, ground, roof, {256, 256}, 200);
  PairMotion motion;
  motion.translation = ground;
  const std::optional<double> below = centreDepthRatio(older, newer, motion);
  ASSERT_TRUE(below.has_value());
  EXPECT_NEAR(*below, 0.625, 0.01);
  // Beside the roof, the ground.
  const std::optional<double> beside = centreDepthRatio(older, newer, motion, {0.0, -170.0});
  ASSERT_TRUE(beside.has_value());
  EXPECT_NEAR(*beside, 1.0, 0.01);
  // A tilted camera's beam (opticalAxisInNadirView) reads beside the centre: 10 deg of roll at
  // fx 443 px is 78 px.
  CameraTilt tilt;
  tilt.roll = 10.0 * M_PI / 180.0;
  const Eigen::Vector2d at = opticalAxisInNadirView(tilt, 443.0);
  EXPECT_NEAR(at.norm(), 443.0 * std::tan(tilt.roll), 1e-6);
  EXPECT_NEAR(opticalAxisInNadirView(CameraTilt{}, 443.0).norm(), 0.0, 1e-12);
  // The frame's beam is that point when the frame was levelled, its centre when taken as level.
  EXPECT_NEAR(beamInFrame(tilt, 443.0).x, at.x(), 1e-12);
  EXPECT_NEAR(beamInFrame(tilt, 443.0).y, at.y(), 1e-12);
  EXPECT_EQ(beamInFrame(std::nullopt, 443.0), cv::Point2d(0.0, 0.0));
}

TEST(CentreDepthRatio, NothingWhenItCannotBeTold) {
  const int n = 512;
  const cv::Mat1f older = texture(n, 1);
  const cv::Mat1f newer = newerFrame(older, {30.0, 10.0}, {30.0, 10.0}, {256, 256}, 0);
  PairMotion motion;
  motion.translation = {30.0, 10.0};
  // A flat centre: no peak stands out of the noise.
  const cv::Mat1f flat(n, n, 128.0f);
  EXPECT_FALSE(centreDepthRatio(flat, flat, motion).has_value());
  // Unrelated frames.
  EXPECT_FALSE(centreDepthRatio(older, texture(n, 7), motion).has_value());
  // The beam's patch outside the frame, no motion, frames of different sizes, a non-finite beam.
  EXPECT_FALSE(centreDepthRatio(older, newer, motion, {300.0, 0.0}).has_value());
  EXPECT_FALSE(centreDepthRatio(older, newer, PairMotion()).has_value());
  EXPECT_FALSE(centreDepthRatio(older, texture(256, 1), motion).has_value());
  EXPECT_FALSE(centreDepthRatio(older, newer, motion, {std::nan(""), 0.0}).has_value());
  // The same ground everywhere: ratio 1.
  ASSERT_TRUE(centreDepthRatio(older, newer, motion).has_value());
  EXPECT_NEAR(*centreDepthRatio(older, newer, motion), 1.0, 0.01);
}

}  // namespace
}  // namespace oefmt
