// SPDX-License-Identifier: GPL-3.0-or-later
// A pair too weak to register on its own is tracked where the depth layers in its energy vector
// still stand at the ratios they held and give the length the motion so far predicts; and only
// then.
#include <gtest/gtest.h>

#include <cmath>
#include <optional>
#include <vector>

#include "oefmt/estimation/estimator.h"
#include "oefmt/evaluation/evaluation.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/texture.h"
#include "support/flight_fixtures.h"

namespace oefmt {
namespace {

// A line over blocks whose tops stand at 40 % of the 20 m altitude, walls in view, the heading
// on the track: at some frames the roofs fill most of the view and their texture leaves the
// translation peak too flat to trust alone (the start of a generalization corpus flight, of
// which the tests fly the first 56 frames).
sim::FlightOptions roofLine() { return test::roofLine(12); }

// The true step from frame k - 1 to k on the ground, in pixels.
double groundStepPixels(const sim::FlightPlan& plan, std::size_t k) {
  const double metres = std::hypot(plan.poses[k].position[0] - plan.poses[k - 1].position[0],
                                   plan.poses[k].position[1] - plan.poses[k - 1].position[1]);
  return metres * plan.camera.intrinsics.fx / plan.track.altitude;
}

// Flies `plan`: every frame after the first is tracked, and each pair too weak to register on
// its own was tracked, degraded, on the length vouched for, within 2 % of the ground's true step
// (the layer followed from the start). `weak_tracked` counts those pairs; the positions go to
// `estimate` and `truth`.
void flyCheckingWeakPairs(const sim::FlightPlan& plan, int& weak_tracked, StampedTrajectory& estimate,
                          StampedTrajectory& truth) {
  const std::vector<cv::Mat1b> frames = test::renderPlan(plan);
  Estimator estimator(test::simulatedFlightConfig(plan));
  weak_tracked = 0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const std::optional<Estimate> e = estimator.push(frames[k], plan.stamps[k]);
    ASSERT_TRUE(e) << "frame " << k;
    test::appendPositions(e->pose, plan.poses[k], k, estimate, truth);
    if (k == 0) continue;
    EXPECT_EQ(e->state, TrackingState::kTracking) << "frame " << k;
    if (e->state != TrackingState::kTracking || e->registration12.usable()) continue;
    ++weak_tracked;
    const double truth_px = groundStepPixels(plan, k);
    EXPECT_TRUE(e->degraded) << "frame " << k;
    EXPECT_NEAR(e->step.shift(), truth_px, 0.02 * truth_px) << "frame " << k;
    EXPECT_DOUBLE_EQ(e->vouched_length, e->step.shift()) << "frame " << k;
  }
}

TEST(CorroboratedSteps, AWeakPairWhoseLayersHoldTheirRatiosIsTracked) {
  int weak_tracked = 0;
  StampedTrajectory estimate, truth;
  ASSERT_NO_FATAL_FAILURE(
      flyCheckingWeakPairs(test::plannedFlight(roofLine(), 56), weak_tracked, estimate, truth));
  // The premise: some pair was too weak to register on its own.
  EXPECT_GE(weak_tracked, 1);
  EvaluationOptions options;
  options.association = AssociationMode::kIndex;
  const EvaluationResult result = evaluateTrajectory(estimate, truth, options);
  EXPECT_LT(result.ate.mean, 0.004 * 111.1) << "111 m flown";
}

// The same line with another seed, flown from its sixth frame: roofs fill the view two frames in,
// long before the layer memory has held any ratio (it needs most of a window of steps). The
// followed layer's own weak peak, at the length the motion so far predicts, carries the pair.
TEST(CorroboratedSteps, BeforeAnyRatioHeldTheFollowedLayersOwnPeakVouches) {
  sim::FlightOptions options = roofLine();
  options.seed = 34;
  sim::FlightPlan plan = test::plannedFlight(options, 30);
  const int first = 6;
  plan.poses.erase(plan.poses.begin(), plan.poses.begin() + first);
  plan.stamps.erase(plan.stamps.begin(), plan.stamps.begin() + first);
  int weak_tracked = 0;
  StampedTrajectory estimate, truth;
  ASSERT_NO_FATAL_FAILURE(flyCheckingWeakPairs(plan, weak_tracked, estimate, truth));
  EXPECT_GE(weak_tracked, 1);
}

// The same flight from its first frame: eight frames in, the roofs' peak stands twenty times
// higher than the ground's, the followed layer, which is still a layer of the energy vector
// (tracking.layer_min_fraction of its maximum) at the predicted length.
TEST(CorroboratedSteps, AFollowedLayerFarBelowTheHighestOneStillVouches) {
  sim::FlightOptions options = roofLine();
  options.seed = 34;
  int weak_tracked = 0;
  StampedTrajectory estimate, truth;
  ASSERT_NO_FATAL_FAILURE(flyCheckingWeakPairs(test::plannedFlight(options, 12), weak_tracked, estimate, truth));
  EXPECT_GE(weak_tracked, 1);
}

// The corpus's tiles figure-8 (tiles on every layer, walls), through its 79th frame. There the
// pair's highest correlation peak is a period of the tiles a few pixels from no shift, in another
// direction than the motion, with no confidence: the layers read along that peak's direction
// vouch for nothing. Read along the predicted direction they vouch for the followed layer's
// length, and the step takes it in the predicted direction (Estimator: corroborated along the
// prediction). Without that reading the frame was not tracked.
TEST(CorroboratedSteps, AnAliasOffTheMotionLeavesTheLayersAlongThePredictedDirectionToVouch) {
  const sim::FlightOptions options = test::tiledFigureEight();
  const sim::FlightPlan plan = test::plannedFlight(options, 80);
  const std::vector<cv::Mat1b> frames = test::renderPlan(plan);
  Estimator estimator(test::simulatedFlightConfig(plan));
  int off_motion = 0;
  // Each step's length over the true one (metric: the altitude is known). The flight follows a
  // raised layer at times, whose steps in pixels differ from the ground's, so the test asks the
  // vouched step to keep the ratio of the step before it.
  std::optional<Pose4> last;
  double last_ratio = 0.0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const std::optional<Estimate> e = estimator.push(frames[k], plan.stamps[k]);
    ASSERT_TRUE(e) << "frame " << k;
    const Pose4 pose = e->pose;
    const std::optional<Pose4> before = last;
    last = pose;
    if (k == 0) continue;
    EXPECT_EQ(e->state, TrackingState::kTracking) << "frame " << k;
    const double estimated = std::hypot(pose.x - before->x, pose.y - before->y);
    const double true_step = std::hypot(plan.poses[k].position[0] - plan.poses[k - 1].position[0],
                                        plan.poses[k].position[1] - plan.poses[k - 1].position[1]);
    const double ratio = estimated / true_step, previous_ratio = last_ratio;
    last_ratio = ratio;
    const PairRegistration& r = e->registration12;
    // The premise: the pair's own peak is far shorter than the step and points elsewhere.
    if (r.usable() || !(cv::norm(r.translation) < 0.25 * e->step.shift())) continue;
    ++off_motion;
    EXPECT_EQ(e->length_source, LengthSource::kVouched) << "frame " << k;
    EXPECT_TRUE(e->degraded) << "frame " << k;
    ASSERT_GT(previous_ratio, 0.0) << "frame " << k;
    EXPECT_NEAR(ratio, previous_ratio, 0.02 * previous_ratio) << "frame " << k;
  }
  EXPECT_GE(off_motion, 1) << "the premise: a pair whose highest peak is an alias near no shift";
}

}  // namespace
}  // namespace oefmt
