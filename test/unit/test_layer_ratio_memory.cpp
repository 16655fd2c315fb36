// SPDX-License-Identifier: GPL-3.0-or-later
// The followed layer's length against the depth layers in view: ratios that held over the last
// steps vouch for the length of a step that broke them (a layer taken for another, an alias).
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <vector>

#include "oefmt/error.h"
#include "oefmt/estimation/layer_ratio_memory.h"

namespace oefmt {
namespace {

constexpr int kFrames = 12, kSupport = 8;
constexpr double kTolerance = 0.01;

// A roof whose shift is 1.43 times the ground's is followed; `speed` scales every shift alike.
void rememberRoofOverGround(LayerRatioMemory& memory, int steps, double speed = 1.0) {
  for (int k = 0; k < steps; ++k) memory.remember(132.4 * speed, {92.6 * speed, 132.4 * speed});
}

TEST(LayerRatioMemory, TheGroundVouchesForTheRoofsLengthAfterTheRoofLeftTheView) {
  LayerRatioMemory memory(kFrames, kSupport, kTolerance);
  rememberRoofOverGround(memory, kFrames);
  // The roof is gone; another roof came in at 120 px. The step read 121.9 px (that roof's, in
  // place of the followed one's); the motion so far says 132.4.
  const std::optional<double> vouched = memory.vouchedLength({92.6, 120.0}, 132.4);
  ASSERT_TRUE(vouched.has_value());
  EXPECT_NEAR(*vouched, 132.4, 0.2);
}

TEST(LayerRatioMemory, RatiosDoNotDependOnTheSpeed) {
  LayerRatioMemory memory(kFrames, kSupport, kTolerance);
  // The vehicle speeds up by 3 % a step: every shift grows, no ratio changes.
  for (int k = 0; k < kFrames; ++k) {
    const double speed = 1.0 + 0.03 * k;
    memory.remember(132.4 * speed, {92.6 * speed, 132.4 * speed});
  }
  const double speed = 1.0 + 0.03 * kFrames;
  const std::optional<double> vouched = memory.vouchedLength({92.6 * speed}, 132.4 * speed);
  ASSERT_TRUE(vouched.has_value());
  EXPECT_NEAR(*vouched, 132.4 * speed, 0.2);
}

TEST(LayerRatioMemory, TwoLayersThatAgreeOutvoteTheNearestLength) {
  LayerRatioMemory memory(kFrames, kSupport, kTolerance);
  for (int k = 0; k < kFrames; ++k) memory.remember(100.0, {100.0, 80.0});
  // Both layers in view give 100 (1.0 x 100 and 1.25 x 80); the wrong pairings give 80 and 125,
  // one vote each, however near the motion so far they lie.
  const std::optional<double> vouched = memory.vouchedLength({100.0, 80.0}, 81.0);
  ASSERT_TRUE(vouched.has_value());
  EXPECT_NEAR(*vouched, 100.0, 1e-9);
}

TEST(LayerRatioMemory, VouchCountsThePairsThatGiveTheLength) {
  LayerRatioMemory memory(kFrames, kSupport, kTolerance);
  for (int k = 0; k < kFrames; ++k) memory.remember(100.0, {100.0, 80.0});
  const std::optional<LayerRatioMemory::Vouched> both = memory.vouch({100.0, 80.0}, 81.0);
  ASSERT_TRUE(both.has_value());
  EXPECT_NEAR(both->length, 100.0, 1e-9);
  EXPECT_EQ(both->votes, 2);
  // Only the roof in view: each ratio gives a length of its own, one vote each; the one nearest
  // the motion so far.
  const std::optional<LayerRatioMemory::Vouched> roof = memory.vouch({80.0}, 97.0);
  ASSERT_TRUE(roof.has_value());
  EXPECT_NEAR(roof->length, 100.0, 1e-9);
  EXPECT_EQ(roof->votes, 1);
  EXPECT_FALSE(memory.vouch({}, 100.0).has_value());
}

TEST(LayerRatioMemory, ARatioMustHaveHeldLongEnough) {
  LayerRatioMemory memory(kFrames, kSupport, kTolerance);
  rememberRoofOverGround(memory, kSupport - 1);
  EXPECT_FALSE(memory.vouchedLength({92.6, 120.0}, 132.4).has_value());
  memory.remember(132.4, {92.6, 132.4});
  EXPECT_TRUE(memory.vouchedLength({92.6, 120.0}, 132.4).has_value());
}

TEST(LayerRatioMemory, AStepThatBrokeTheRatiosSilencesItUntilItsOwnHaveHeld) {
  LayerRatioMemory memory(kFrames, kSupport, kTolerance);
  rememberRoofOverGround(memory, kFrames);
  // A step 6 % long against the same layers slipped through (an alias took the length). Its
  // ratios have not held: the memory vouches for nothing rather than fight it.
  memory.remember(140.3, {92.6, 132.4});
  EXPECT_FALSE(memory.vouchedLength({92.6, 132.4}, 140.3).has_value());
  // Seven more such steps and its ratios have held in 8 of the last 12: the new scale is vouched
  // for as the old one was.
  for (int k = 1; k < kSupport - 1; ++k) memory.remember(140.3, {92.6, 132.4});
  EXPECT_FALSE(memory.vouchedLength({92.6, 132.4}, 140.3).has_value());
  memory.remember(140.3, {92.6, 132.4});
  const std::optional<double> vouched = memory.vouchedLength({92.6, 120.0}, 140.3);
  ASSERT_TRUE(vouched.has_value());
  EXPECT_NEAR(*vouched, 140.3, 0.2);
}

TEST(LayerRatioMemory, ClearForgetsEveryRatio) {
  LayerRatioMemory memory(kFrames, kSupport, kTolerance);
  rememberRoofOverGround(memory, kFrames);
  memory.clear();
  EXPECT_FALSE(memory.vouchedLength({92.6}, 132.4).has_value());
}

TEST(LayerRatioMemory, RejectsInvalidSettings) {
  EXPECT_THROW(LayerRatioMemory(0, 1, kTolerance), InputError);
  EXPECT_THROW(LayerRatioMemory(4, 5, kTolerance), InputError);
  EXPECT_THROW(LayerRatioMemory(4, 2, 0.0), InputError);
  EXPECT_THROW(LayerRatioMemory(4, 2, 1.0), InputError);
}

TEST(LayerRatioMemory, IgnoresShiftsThatAreNotLengths) {
  LayerRatioMemory memory(kFrames, kSupport, kTolerance);
  for (int k = 0; k < kFrames; ++k) memory.remember(100.0, {100.0, 0.0, -5.0, std::nan("")});
  const std::optional<double> vouched = memory.vouchedLength({50.0, 0.0, std::nan("")}, 50.0);
  ASSERT_TRUE(vouched.has_value());
  EXPECT_NEAR(*vouched, 50.0, 1e-9);
}

}  // namespace
}  // namespace oefmt
