// SPDX-License-Identifier: GPL-3.0-or-later
// The rotation surface reads a turn of a fraction of a bin a few hundredths of a bin off (towards
// or away from the whole bin, depending on the fraction). In a steady turn every pair has the
// same fraction, so the error is the same each frame and the heading drifts by it. The zoom
// refinement reads the rotation on the intensities as well; weighed against the surface's by
// their sigmas, the pair's rotation loses most of that bias.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numeric>
#include <vector>

#include "oefmt/estimation/estimator.h"
#include "oefmt/sim/flight.h"
#include "support/flight_fixtures.h"

namespace oefmt {
namespace {

constexpr int kFrames = 12;

sim::FlightPlan steadyTurn(double degrees_per_frame) {
  sim::FlightOptions options;
  options.track.shape = sim::TrackShape::kSpin;
  options.track.spin_rate = degrees_per_frame * CV_PI / 180.0;
  options.seed = 43;
  return test::plannedFlight(options, kFrames);
}

// Mean error of the heading steps, in bins of the rotation surface (pi / N rad).
double headingBiasBins(const sim::FlightPlan& plan, const std::vector<cv::Mat1b>& frames,
                       double refined_rotation_scale) {
  EstimatorConfig config = test::simulatedFlightConfig(plan);
  config.uncertainty.refined_rotation_scale = refined_rotation_scale;
  Estimator estimator(config);
  const test::FlownPlan flown = test::flyPlan(estimator, plan, frames);
  for (const std::size_t k : flown.refused) ADD_FAILURE() << "frame " << k << " refused";
  const std::vector<double>& errors = flown.heading_step_errors;
  if (errors.empty()) return 0.0;
  return std::accumulate(errors.begin(), errors.end(), 0.0) / errors.size() * config.registration.size / CV_PI;
}

TEST(SteadyTurnHeading, TheRefinedRotationTakesOutTheSurfacesSubBinBias) {
  const double default_scale = EstimatorConfig{}.uncertainty.refined_rotation_scale;
  for (const double degrees : {1.0, 1.8}) {
    const sim::FlightPlan plan = steadyTurn(degrees);
    const std::vector<cv::Mat1b> frames = test::renderPlan(plan);
    const double weighed = headingBiasBins(plan, frames, default_scale);
    const double surface = headingBiasBins(plan, frames, 100.0);  // the refinement weighs ~nothing
    std::printf("[ steady turn ] %.1f deg per frame: heading bias %.4f bins (surface alone %.4f bins)\n",
                degrees, weighed, surface);
    EXPECT_GT(std::fabs(surface), 0.015) << "the premise: the surface alone is biased at this fraction";
    EXPECT_LT(std::fabs(weighed), 0.012);
    EXPECT_LT(std::fabs(weighed), 0.5 * std::fabs(surface));
  }
}

}  // namespace
}  // namespace oefmt
