// SPDX-License-Identifier: GPL-3.0-or-later
// Registration over a lattice of dense block tops, where the highest rotation/zoom peak is a
// quarter turn: the next peaks are tried until the translation confirms one.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "oefmt/registration/registration.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/renderer.h"
#include "support/fixtures.h"

namespace oefmt {
namespace {

// Frames 71 and 72 (1-based, as oefmt_simulate names them) of `oefmt_simulate --raised 1
// --fill 0.8` with two raised levels at 0.15 and 0.30 of the altitude (the default levels until
// the third was added): a level flight with fixed heading, so the truth is no rotation, no
// zoom, and the ground's shift of about 92.6 px.
struct LatticePair {
  cv::Mat1b older, newer;
  double ground_shift = 0.0;  // [px]
};

LatticePair latticePair() {
  sim::FlightOptions options;
  options.raised_share = 1.0;
  options.fill = 0.8;
  options.level_heights = test::levelHeights(options, {0.15, 0.30});
  const sim::FlightPlan plan = sim::planFlight(options);
  const sim::Renderer renderer(std::make_shared<const sim::Scene>(plan.scene), plan.camera, plan.supersample);
  LatticePair pair;
  pair.older = sim::sensorImage(renderer.render(plan.poses[70]).image, plan.sensor, plan.scene.seed, 70);
  pair.newer = sim::sensorImage(renderer.render(plan.poses[71]).image, plan.sensor, plan.scene.seed, 71);
  const cv::Vec3d step = plan.poses[71].position - plan.poses[70].position;
  pair.ground_shift = std::hypot(step[0], step[1]) * plan.camera.intrinsics.fx / plan.track.altitude;
  return pair;
}

PairRegistration registerWith(const LatticePair& pair, int candidates) {
  RegistrationConfig config;
  config.fft_planning = FftPlanning::kEstimate;
  config.rotation_zoom_candidates = candidates;
  Registrar registrar(config);
  return registrar.registerPair(registrar.analyse(pair.older), registrar.analyse(pair.newer));
}

TEST(RotationZoomCandidates, ALatticeQuarterTurnGivesWayToTheRightPeak) {
  const LatticePair pair = latticePair();
  // Only the highest peak: a quarter turn, which the translation refuses.
  const PairRegistration first = registerWith(pair, 1);
  EXPECT_EQ(first.status, RegistrationStatus::kLowConfidence);
  EXPECT_NEAR(std::fabs(first.rotation), CV_PI / 2, 0.05);

  const PairRegistration r = registerWith(pair, RegistrationConfig().rotation_zoom_candidates);
  ASSERT_EQ(r.status, RegistrationStatus::kOk);
  EXPECT_GT(r.rotation_zoom_candidate, 0);
  EXPECT_NEAR(r.rotation, 0.0, 0.01);
  EXPECT_NEAR(std::log(r.zoom), 0.0, 0.005);
  EXPECT_NEAR(r.shift, pair.ground_shift, 1.0);
}

}  // namespace
}  // namespace oefmt
