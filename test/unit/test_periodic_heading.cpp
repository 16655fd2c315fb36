// SPDX-License-Identifier: GPL-3.0-or-later
// A strictly periodic texture (running-bond bricks) looks the same turned by half a turn, so the
// rotation surface, which reads the rotation modulo a half turn, cannot tell the heading from its
// reverse, and the translation correlation of the reversed frame is as clean as the true one's.
// The vehicle's largest yaw rate decides it: between frames 0.2 s apart no vehicle turns by a
// quarter turn. Without that bound the flat brick line flips its heading (the whole flight then
// zig-zags); with it every heading step is right and the line is tracked.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "oefmt/estimation/estimator.h"
#include "oefmt/evaluation/evaluation.h"
#include "oefmt/registration/registration.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/texture.h"
#include "support/flight_fixtures.h"

namespace oefmt {
namespace {

// A level line over flat brick ground (the generalization corpus's kind of flight, another seed).
sim::FlightPlan brickLine(int frames) {
  sim::FlightOptions options;
  options.track.shape = sim::TrackShape::kLine;
  options.flat = true;
  options.texture_styles = {sim::TextureStyle::kBrick};
  options.seed = 41;
  return test::plannedFlight(options, frames);
}

struct FlightRun {
  double worst_heading_step_deg = 0.0;
  double drift_percent = 0.0;
};

FlightRun fly(const sim::FlightPlan& plan, const std::vector<cv::Mat1b>& frames, double max_yaw_rate) {
  EstimatorConfig config = test::simulatedFlightConfig(plan);
  config.tracking.max_yaw_rate = max_yaw_rate;
  Estimator estimator(config);
  const test::FlownPlan flown = test::flyPlan(estimator, plan, frames);
  for (const std::size_t k : flown.refused) ADD_FAILURE() << "frame " << k << " refused";
  FlightRun run;
  for (const double error : flown.heading_step_errors) {
    run.worst_heading_step_deg = std::max(run.worst_heading_step_deg, std::fabs(error) * 180.0 / M_PI);
  }
  EvaluationOptions options;
  options.association = AssociationMode::kIndex;
  run.drift_percent = evaluateTrajectory(flown.estimate, flown.truth, options).drift_percent;
  return run;
}

TEST(PeriodicHeading, BrickTextureReadsTheSameTurnedByHalfATurn) {
  // The premise: the two readings of the rotation are equally good matches on this texture.
  const sim::FlightPlan plan = brickLine(2);
  const std::vector<cv::Mat1b> frames = test::renderPlan(plan);
  RegistrationConfig config;
  config.fft_planning = FftPlanning::kEstimate;
  Registrar registrar(config);
  const FrameSpectra a = registrar.analyse(frames[0]), b = registrar.analyse(frames[1]);
  const PairRegistration unbounded = registrar.registerPair(a, b);
  const PairRegistration bounded = registrar.registerPair(a, b, RegistrationMethod::kEnergyVectors, nullptr,
                                                          nullptr, CV_PI / 4.0);
  EXPECT_GT(std::fabs(unbounded.rotation), CV_PI / 2.0) << "the premise: the reverse reads as well or better";
  EXPECT_LT(std::fabs(bounded.rotation), 0.01) << "the smaller turn";
  EXPECT_TRUE(bounded.usable());
  std::printf("[ periodic heading ] first pair's rotation: %.4f rad unbounded, %.4f rad within a quarter turn\n",
              unbounded.rotation, bounded.rotation);
}

TEST(PeriodicHeading, TheYawRateBoundKeepsTheHeadingOnABrickLine) {
  const sim::FlightPlan plan = brickLine(30);
  ASSERT_LT(plan.stamps[1] - plan.stamps[0], 0.5) << "frames close enough in time that a turn is bounded";
  const std::vector<cv::Mat1b> frames = test::renderPlan(plan);
  const FlightRun bounded = fly(plan, frames, EstimatorConfig{}.tracking.max_yaw_rate);
  const FlightRun unbounded = fly(plan, frames, 1000.0);  // any turn is possible between frames
  std::printf("[ periodic heading ] worst heading step %.2f deg, drift %.2f %% (unbounded yaw rate: %.2f deg, %.2f %%)\n",
              bounded.worst_heading_step_deg, bounded.drift_percent, unbounded.worst_heading_step_deg,
              unbounded.drift_percent);
  EXPECT_LT(bounded.worst_heading_step_deg, 2.0);
  EXPECT_LT(bounded.drift_percent, 0.5);
  EXPECT_GT(unbounded.worst_heading_step_deg, 90.0) << "without the bound the heading flips (the check can fail)";
}

}  // namespace
}  // namespace oefmt
