// SPDX-License-Identifier: GPL-3.0-or-later
// A pair that no motion so far predicts (the first pair of a flight, or the first after a
// restart) is registered from the whole rotation/zoom surface. At low overlap the two frames
// share little, and the surface's highest peaks can all be wrong: the pair then does not register.
// The vehicle may simply have held its heading and altitude, and that is tried next, within the
// turn the vehicle can make: a figure-8 at 65 % overlap whose first pairs failed (three frames
// held, a restart) now tracks from its first frame.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "oefmt/estimation/estimator.h"
#include "oefmt/registration/registration.h"
#include "oefmt/sim/flight.h"
#include "support/flight_fixtures.h"

namespace oefmt {
namespace {

sim::FlightPlan lowOverlapEight(int frames) {
  sim::FlightOptions options;
  options.track.shape = sim::TrackShape::kEight;
  options.overlap = 0.65;
  options.seed = 4;
  return test::plannedFlight(options, frames);
}

TEST(UnpredictedPair, ALowOverlapFirstPairRegistersAsTheVehicleHoldingHeadingAndAltitude) {
  const sim::FlightPlan plan = lowOverlapEight(6);
  const std::vector<cv::Mat1b> frames = test::renderPlan(plan);

  // The premise: the surface's peaks alone do not register the first pair.
  RegistrationConfig registration;
  registration.fft_planning = FftPlanning::kEstimate;
  Registrar registrar(registration);
  const PairRegistration alone = registrar.registerPair(registrar.analyse(frames[0]), registrar.analyse(frames[1]));
  EXPECT_FALSE(alone.usable()) << "the first pair registered without help (rotation " << alone.rotation << ")";

  const EstimatorConfig config = test::simulatedFlightConfig(plan);
  Estimator estimator(config);
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const std::optional<Estimate> e = estimator.push(frames[k], plan.stamps[k]);
    ASSERT_TRUE(e.has_value());
    if (k == 0) continue;
    EXPECT_EQ(e->state, TrackingState::kTracking) << "frame " << k;
    // Each step against the truth: the ground distance within 2 %, no turn.
    const double true_step = std::hypot(plan.poses[k].position[0] - plan.poses[k - 1].position[0],
                                        plan.poses[k].position[1] - plan.poses[k - 1].position[1]);
    EXPECT_NEAR(std::hypot(e->step.translation.x, e->step.translation.y) * plan.track.altitude /
                    config.working_fx,
                true_step, 0.02 * true_step)
        << "frame " << k;
    EXPECT_NEAR(e->step.rotation, 0.0, 0.01) << "frame " << k;
  }
}

}  // namespace
}  // namespace oefmt
