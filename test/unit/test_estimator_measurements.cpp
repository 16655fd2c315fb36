// SPDX-License-Identifier: GPL-3.0-or-later
// The estimator's internal decisions on one pair's observations (src/core/estimator_measurements).
#include <gtest/gtest.h>

#include "estimator_measurements.h"

namespace oefmt {
namespace {

PairMotion motionAlongX(double shift) {
  PairMotion m;
  m.translation = {shift, 0.0};
  m.translation_covariance = cv::Matx22d::eye();
  return m;
}

detail::Reference referenceOf(double shift) {
  detail::Reference ref;
  ref.translation = {shift, 0.0};
  ref.shift = shift;
  ref.shift_sigma = 0.5;
  return ref;
}

// Pair 0-1 moved 92.7 px. A stretch that matched the ground of one energy vector to a higher
// layer of the other makes the step 1.47 times as long while the dominant peak says 92.6 px:
// without a loop to confirm the switch, the steadier dominant peak is kept.
TEST(SteadierLayerStep, AWrongStretchDoesNotRescaleTheFlight) {
  const PairMotion candidate = motionAlongX(136.3), measured = motionAlongX(92.6);
  const PairMotion step = detail::steadierLayerStep(candidate, measured, true,
                                                referenceOf(92.7), 1.0);
  EXPECT_DOUBLE_EQ(step.shift(), 92.6);
}

// The roofs took over the correlation peak (1.4 times the ground's shift) while PMT followed
// the ground at steady speed: the switch PMT proposed is kept.
TEST(SteadierLayerStep, ARoofTakingOverThePeakStillFollowsTheGround) {
  const PairMotion candidate = motionAlongX(93.0), measured = motionAlongX(129.8);
  const PairMotion step = detail::steadierLayerStep(candidate, measured, true,
                                                referenceOf(92.7), 1.0);
  EXPECT_DOUBLE_EQ(step.shift(), 93.0);
}

// Pair 0-2 spans two of pair 0-1's intervals: steady speed means twice its shift.
TEST(SteadierLayerStep, SteadySpeedScalesWithTheFrameIntervals) {
  const PairMotion candidate = motionAlongX(185.0), measured = motionAlongX(130.0);
  const PairMotion step = detail::steadierLayerStep(candidate, measured, true,
                                                referenceOf(92.7), 2.0);
  EXPECT_DOUBLE_EQ(step.shift(), 185.0);
}

// Without a proposed switch, or without a reference length, the candidate step stands.
TEST(SteadierLayerStep, NoSwitchOrNoReferenceKeepsTheGatedStep) {
  const PairMotion candidate = motionAlongX(136.3), measured = motionAlongX(92.6);
  EXPECT_DOUBLE_EQ(detail::steadierLayerStep(candidate, measured, false,
                                         referenceOf(92.7), 1.0).shift(), 136.3);
  EXPECT_DOUBLE_EQ(detail::steadierLayerStep(candidate, measured, true,
                                         referenceOf(0.0), 1.0).shift(), 136.3);
  EXPECT_DOUBLE_EQ(detail::steadierLayerStep(candidate, motionAlongX(0.0), true,
                                         referenceOf(92.7), 1.0).shift(), 136.3);
}

}  // namespace
}  // namespace oefmt
