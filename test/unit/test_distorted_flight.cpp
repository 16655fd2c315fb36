// SPDX-License-Identifier: GPL-3.0-or-later
// A flight seen through a barrel lens (k1 -0.2, k2 0.05, as a user's rendered flight) registers
// as well, once undistorted, as the same flight (same poses, same scene) seen through a pinhole:
// the same trajectory error and drift within a small margin, and equally good heading steps.
// The same checks on the distorted frames taken as they are fail by far (the check can fail).
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <memory>
#include <vector>

#include "oefmt/error.h"
#include "oefmt/estimation/estimator.h"
#include "oefmt/evaluation/evaluation.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/renderer.h"
#include "oefmt/sim/scene.h"
#include "oefmt/io/undistortion.h"
#include "support/flight_fixtures.h"

namespace oefmt {
namespace {

struct FlightRun {
  EvaluationResult result;
  double worst_heading_step = 0.0;  // [deg] largest error of a frame-to-frame yaw change
};

// The first 40 frames of the default circle (2.47 m apart), turning with the track (1.8 deg
// per frame): translation and rotation both matter.
sim::FlightPlan circlePiece() {
  sim::FlightOptions options;
  options.track.heading = sim::HeadingMode::kTrack;
  options.seed = 5;
  return test::plannedFlight(options, 40);
}

std::vector<cv::Mat1b> render(const sim::FlightPlan& plan, const std::shared_ptr<const sim::Scene>& scene,
                              const CameraParameters& camera) {
  const sim::Renderer renderer(scene, camera, plan.supersample);
  std::vector<cv::Mat1b> frames;
  for (std::size_t k = 0; k < plan.poses.size(); ++k) {
    frames.push_back(sim::sensorImage(renderer.render(plan.poses[k]).image, plan.sensor, plan.scene.seed,
                                      static_cast<int>(k)));
  }
  return frames;
}

double wrapDegrees(double radians) { return std::remainder(radians, 2.0 * M_PI) * 180.0 / M_PI; }

FlightRun fly(const sim::FlightPlan& plan, const std::vector<cv::Mat1b>& frames, const Undistorter& camera) {
  EstimatorConfig config;
  config.registration.fft_planning = FftPlanning::kEstimate;
  config.initial_altitude = plan.track.altitude;
  config.working_fx = camera.workingFx();
  Estimator estimator(config);
  StampedTrajectory estimate, truth;
  FlightRun run;
  double previous_yaw = 0.0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const std::optional<Estimate> e = estimator.push(camera.apply(frames[k]), static_cast<double>(k));
    if (!e) {
      ADD_FAILURE() << "frame " << k << " refused";
      continue;
    }
    if (k > 0) {
      const double step_error =
          wrapDegrees((e->pose.yaw - previous_yaw) - (plan.poses[k].yaw - plan.poses[k - 1].yaw));
      run.worst_heading_step = std::max(run.worst_heading_step, std::fabs(step_error));
    }
    previous_yaw = e->pose.yaw;
    test::appendPositions(e->pose, plan.poses[k], k, estimate, truth);
  }
  EvaluationOptions options;
  options.association = AssociationMode::kIndex;
  try {
    run.result = evaluateTrajectory(estimate, truth, options);
  } catch (const InputError&) {
    // Nothing registered (every pose at the origin): as bad as it gets.
    run.result.ate.mean = run.result.drift_percent = std::numeric_limits<double>::infinity();
  }
  return run;
}

// Registers "as well as" the pinhole flight. The margins allow for what undistorting costs: the
// frames lose some sharpness (resampling; a barrel lens also has fewer pixels for the
// periphery), about a Gaussian blur of half a pixel, and on this multi-depth scene that is
// enough to tip an occasional marginal pair to another layer's peak (a pinhole pair blurred as
// much does the same). So the undistorted flight's error may be a small multiple of the pinhole
// flight's, as it was over flights of several tracks and scenes where neither lost track (a
// flight that loses track once restarts with a new scale and can be further off), and its
// heading steps stay within the threshold. The distorted frames taken as they are fail by far:
// metres of error, drift of tens of percent.
::testing::AssertionResult registersAsWell(const FlightRun& run, const FlightRun& pinhole) {
  const double ate = run.result.ate.mean, pinhole_ate = pinhole.result.ate.mean;
  const double drift = run.result.drift_percent, pinhole_drift = pinhole.result.drift_percent;
  ::testing::AssertionResult result =
      (ate <= 2.0 * pinhole_ate + 0.1 && drift <= pinhole_drift + 1.0 && run.worst_heading_step <= 2.0)
          ? ::testing::AssertionSuccess()
          : ::testing::AssertionFailure();
  return result << "ATE mean " << ate << " m (pinhole " << pinhole_ate << " m), drift " << drift << " % (pinhole "
                << pinhole_drift << " %), worst heading step error " << run.worst_heading_step << " deg (pinhole "
                << pinhole.worst_heading_step << " deg)";
}

TEST(DistortedFlight, UndistortedRegistersAsWellAsThePinholeFlight) {
  const sim::FlightPlan plan = circlePiece();
  const auto scene = std::make_shared<const sim::Scene>(plan.scene);
  CameraParameters lens = plan.camera;
  lens.distortion.k1 = -0.2;
  lens.distortion.k2 = 0.05;
  const cv::Size size(plan.camera.intrinsics.width, plan.camera.intrinsics.height);

  const int n = EstimatorConfig{}.registration.size;
  const FlightRun pinhole = fly(plan, render(plan, scene, plan.camera), Undistorter(plan.camera, size, n));
  const std::vector<cv::Mat1b> distorted = render(plan, scene, lens);
  const FlightRun undistorted = fly(plan, distorted, Undistorter(lens, size, n));
  CameraParameters ignored = lens;
  ignored.distortion = Distortion{};
  const FlightRun as_they_are = fly(plan, distorted, Undistorter(ignored, size, n));

  EXPECT_LT(pinhole.result.ate.mean, 0.2) << "the pinhole flight itself registers";
  EXPECT_TRUE(registersAsWell(undistorted, pinhole));
  EXPECT_FALSE(registersAsWell(as_they_are, pinhole)) << "the check cannot tell";
  std::printf("[ distorted flight ] pinhole: %s\n[ distorted flight ] undistorted: %s\n"
              "[ distorted flight ] as they are: %s\n",
              registersAsWell(pinhole, pinhole).message(), registersAsWell(undistorted, pinhole).message(),
              registersAsWell(as_they_are, pinhole).message());
}

}  // namespace
}  // namespace oefmt
