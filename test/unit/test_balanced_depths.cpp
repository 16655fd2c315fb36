// SPDX-License-Identifier: GPL-3.0-or-later
// o-eFMT's reason to exist: a scene of several depths with comparable areas, where the dominant
// correlation peak hops between layers. The classic method's scale hops with it; o-eFMT must
// keep following one layer (pattern matching + loop), and must not be lured onto another one.
#include <gtest/gtest.h>

#include <vector>

#include "oefmt/estimation/estimator.h"
#include "oefmt/evaluation/evaluation.h"
#include "oefmt/sim/flight.h"
#include "support/fixtures.h"
#include "support/flight_fixtures.h"

namespace oefmt {
namespace {

// A short circle (40 frames of 2.45 m, as the default circle's) over terraces at 0.15 and 0.30
// of the altitude covering most of the ground, flat (no incline): the ground's and the roofs'
// peaks take turns as the largest.
sim::FlightOptions balancedFlight() {
  sim::FlightOptions options;
  options.track.frames = 40;
  options.track.length = 98.2;
  options.seed = 3;
  options.raised_share = 1.0;
  options.fill = 0.9;
  options.incline_deg = 0.0;
  options.level_heights = test::levelHeights(options, {0.15, 0.30});
  return options;
}

struct FlightRun {
  EvaluationResult result;
  int hops = 0;  // frames whose dominant peak is more than 10 % off the previous frame's
};

FlightRun fly(const sim::FlightPlan& plan, const std::vector<cv::Mat1b>& frames, EstimatorMode mode) {
  EstimatorConfig config;
  config.mode = mode;
  config.registration.fft_planning = FftPlanning::kEstimate;
  config.initial_altitude = plan.track.altitude;
  config.working_fx = plan.camera.intrinsics.fx;
  Estimator estimator(config);
  StampedTrajectory estimate, truth;
  FlightRun run;
  double previous_rho = 0.0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const std::optional<Estimate> e = estimator.push(frames[k], static_cast<double>(k));
    if (!e) {
      ADD_FAILURE() << "frame " << k << " refused";
      continue;
    }
    EXPECT_TRUE(e->pose.finite()) << "frame " << k;
    const double rho = e->registration12.shift;
    if (k > 1 && previous_rho > 0.0 && std::fabs(rho / previous_rho - 1.0) > 0.1) ++run.hops;
    previous_rho = rho;
    test::appendPositions(e->pose, plan.poses[k], k, estimate, truth);
  }
  EvaluationOptions options;
  options.association = AssociationMode::kIndex;
  run.result = evaluateTrajectory(estimate, truth, options);
  return run;
}

TEST(BalancedDepths, OefmtFollowsOneLayerWhereTheDominantPeakHops) {
  const sim::FlightPlan plan = sim::planFlight(balancedFlight());
  std::vector<cv::Mat1b> frames;
  sim::renderFlight(plan, [&](int, const cv::Mat1b& image, const cv::Mat1b&) { frames.push_back(image.clone()); });
  ASSERT_EQ(frames.size(), 40u);

  const FlightRun fmt = fly(plan, frames, EstimatorMode::kFmt);
  const FlightRun oefmt = fly(plan, frames, EstimatorMode::kOefmt);
  // The scene does what it is for: the dominant peak changes layer several times.
  EXPECT_GE(fmt.hops, 4);
  // 98 m flown: o-eFMT within 0.1 m on average, and far better than the hopping classic method.
  EXPECT_LT(oefmt.result.ate.mean, 0.1);
  EXPECT_GT(fmt.result.ate.mean, 5.0 * oefmt.result.ate.mean)
      << "fmt " << fmt.result.ate.mean << " m, oefmt " << oefmt.result.ate.mean << " m";
}

}  // namespace
}  // namespace oefmt
