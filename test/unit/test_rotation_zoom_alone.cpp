// SPDX-License-Identifier: GPL-3.0-or-later
// Pair 0-2 spans twice the motion: over tiles with walls in view, its frames overlapping by about
// half, its translation fails on most frames where pair 1-2's registers. Its rotation/zoom peak
// reads the magnitude spectra, which do not depend on the translation; within the rates' gates the
// loop takes its rotation alone, and that rotation is the turn. (The flight holds its heading: every true turn
// is zero, and every reading's error is its value.)
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <optional>
#include <vector>

#include "estimation/estimator_measurements.h"
#include "oefmt/estimation/estimator.h"
#include "oefmt/sim/flight.h"
#include "support/flight_fixtures.h"

namespace oefmt {
namespace {

TEST(RotationZoomAlone, APairZeroTwoWhoseTranslationFailsClosesTheLoopsTurn) {
  const sim::FlightOptions options = test::tiledFigureEight();
  const sim::FlightPlan plan = test::plannedFlight(options, 140);
  const std::vector<cv::Mat1b> frames = test::renderPlan(plan);
  Estimator estimator(test::simulatedFlightConfig(plan));
  int rotation_only = 0;
  double observed_sq = 0.0, measured_sq = 0.0, loop_sq = 0.0, worst_observed = 0.0;
  double measured_sum = 0.0, loop_sum = 0.0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const std::optional<Estimate> e = estimator.push(frames[k], plan.stamps[k]);
    ASSERT_TRUE(e) << "frame " << k;
    if (k < 2 || !e->rotation_only02) continue;
    ++rotation_only;
    const PairRegistration& r02 = e->registration02;
    // The image turns against the camera.
    const double turn02 = -std::remainder(plan.poses[k].yaw - plan.poses[k - 2].yaw, 2.0 * M_PI);
    const double turn12 = -std::remainder(plan.poses[k].yaw - plan.poses[k - 1].yaw, 2.0 * M_PI);
    EXPECT_FALSE(r02.usable()) << "frame " << k << ": the premise, pair 0-2's translation failed";
    EXPECT_TRUE(r02.rotation_zoom_only) << "frame " << k;
    EXPECT_EQ(e->translation_use02, PairObservations::TranslationUse::kNone) << "frame " << k;
    EXPECT_EQ(e->lambda_t02, 0.0) << "frame " << k << ": no length of pair 0-2's";
    EXPECT_EQ(e->loop.status, OptimizerStatus::kConverged) << "frame " << k;
    const double observed02 = detail::calibrated(r02, UncertaintyConfig{}).rotation;
    observed_sq += (observed02 - turn02) * (observed02 - turn02);
    measured_sq += (e->measured12.rotation - turn12) * (e->measured12.rotation - turn12);
    loop_sq += (e->loop.pair12.rotation - turn12) * (e->loop.pair12.rotation - turn12);
    measured_sum += e->measured12.rotation - turn12;
    loop_sum += e->loop.pair12.rotation - turn12;
    worst_observed = std::max(worst_observed, std::fabs(observed02 - turn02));
  }
  ASSERT_GE(rotation_only, 5) << "the premise: pairs 0-2 whose translation failed";
  const auto rms = [&](double sum_sq) { return 1e3 * std::sqrt(sum_sq / rotation_only); };
  std::printf("[ rotation alone ] %d pairs: rms error of pair 0-2's observed turn %.2f mrad (worst %.2f); "
              "pair 1-2's as measured %.2f (summed %.2f), after the loop %.2f (summed %.2f)\n",
              rotation_only, rms(observed_sq), 1e3 * worst_observed, rms(measured_sq), 1e3 * measured_sum,
              rms(loop_sq), 1e3 * loop_sum);
  EXPECT_LT(rms(observed_sq), 1.0) << "pair 0-2's turn, read without its translation";
  EXPECT_LT(worst_observed, 3e-3);
  EXPECT_LT(rms(loop_sq), rms(measured_sq)) << "the loop brought pair 1-2's turn closer to the truth";
  // The heading adds the steps' errors up: those of one sign in a row are what it keeps.
  EXPECT_LT(std::fabs(loop_sum), 0.75 * std::fabs(measured_sum)) << "and the heading those steps added";
}

}  // namespace
}  // namespace oefmt
