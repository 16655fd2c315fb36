// SPDX-License-Identifier: GPL-3.0-or-later
// Giving the estimator the altitude (for metric output) must not make it track worse. The
// prediction's translation window allows for the vehicle's acceleration at the distance of the
// nearest content the scene may hold: tracking.assumed_altitude, or the known altitude where
// that is lower. Taken at the known altitude alone, the window of a flight at 12-20 m was three
// to four times narrower, too narrow for the prediction's own errors, and the corpus's flat brick
// line drifted 1.2 % with its altitude against 0.04 % without it.
#include <gtest/gtest.h>

#include <cstdio>
#include <vector>

#include "oefmt/estimation/estimator.h"
#include "oefmt/evaluation/evaluation.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/texture.h"
#include "support/flight_fixtures.h"

namespace oefmt {
namespace {

double drift(const sim::FlightPlan& plan, const std::vector<cv::Mat1b>& frames, double initial_altitude) {
  EstimatorConfig config = test::simulatedFlightConfig(plan);
  config.initial_altitude = initial_altitude;
  Estimator estimator(config);
  const test::FlownPlan flown = test::flyPlan(estimator, plan, frames);
  for (const std::size_t k : flown.refused) ADD_FAILURE() << "frame " << k << " refused";
  EvaluationOptions options;
  options.association = AssociationMode::kIndex;
  return evaluateTrajectory(flown.estimate, flown.truth, options).drift_percent;
}

TEST(KnownAltitude, ABrickLineTracksAsWellWithItsAltitudeAsWithout) {
  // The corpus's line-brick-flat: flat running-bond brick ground, a 200 m line in 100 frames.
  sim::FlightOptions options;
  options.track.shape = sim::TrackShape::kLine;
  options.track.length = 200.0;
  options.track.frames = 100;
  options.flat = true;
  options.texture_styles = {sim::TextureStyle::kBrick};
  options.seed = 23;
  const sim::FlightPlan plan = test::plannedFlight(options, 100);
  ASSERT_GT(plan.track.altitude, EstimatorConfig{}.tracking.assumed_altitude)
      << "the premise: a flight above the distance the window allows for";
  const std::vector<cv::Mat1b> frames = test::renderPlan(plan);
  const double known = drift(plan, frames, plan.track.altitude);
  const double unknown = drift(plan, frames, 0.0);
  std::printf("[ known altitude ] drift %.3f %% with the altitude (%.1f m), %.3f %% without\n", known,
              plan.track.altitude, unknown);
  EXPECT_LT(unknown, 0.5);
  EXPECT_LT(known, 0.5);
  EXPECT_NEAR(known, unknown, 0.02);
}

}  // namespace
}  // namespace oefmt
