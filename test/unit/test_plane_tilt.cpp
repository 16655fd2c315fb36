// SPDX-License-Identifier: GPL-3.0-or-later
// A levelled view off by the attitude source's error sees the flat ground as a tilted plane: the
// pair's zoom reads the flight as a climb or descent, and its stretch tells the tilt
// (oefmt/registration/plane_tilt.h); PlaneTiltTracker follows that tilt over the pairs.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <optional>
#include <random>
#include <vector>

#include "estimation/estimator_measurements.h"
#include "oefmt/estimation/estimator.h"
#include "oefmt/estimation/plane_tilt_tracker.h"
#include "oefmt/registration/plane_tilt.h"
#include "oefmt/registration/registration.h"
#include "oefmt/sim/camera_model.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/renderer.h"
#include "support/fixtures.h"

namespace oefmt {
namespace {

constexpr double kDeg = M_PI / 180.0;
constexpr int kN = 256;

// The stretch S = [a b; b -a] of the linear map I - d t^T (a plane of tilt t [1/px] seen by a
// pair that moved by d [px]): the symmetric, trace-free part of -d t^T.
std::pair<double, double> stretchOf(const cv::Point2d& tilt, const cv::Point2d& d) {
  const double m00 = -d.x * tilt.x, m01 = -d.x * tilt.y, m10 = -d.y * tilt.x, m11 = -d.y * tilt.y;
  return {(m00 - m11) / 2.0, (m01 + m10) / 2.0};
}

TEST(PlaneTilt, TheStretchOfATiltedPlaneGivesItsTilt) {
  for (const cv::Point2d d : {cv::Point2d(80.0, 30.0), cv::Point2d(-12.0, 55.0), cv::Point2d(0.0, -40.0)}) {
    for (const cv::Point2d tilt : {cv::Point2d(3e-5, -2e-5), cv::Point2d(-1e-4, 0.0), cv::Point2d(0.0, 5e-5)}) {
      const auto [a, b] = stretchOf(tilt, d);
      const cv::Point2d read = tiltFromStretch(a, b, d);
      EXPECT_NEAR(read.x, tilt.x, 1e-12) << d << tilt;
      EXPECT_NEAR(read.y, tilt.y, 1e-12) << d << tilt;
      EXPECT_DOUBLE_EQ(logZoomOfTilt(tilt, d), 1.5 * tilt.dot(d));
      // The turn: the antisymmetric part of -d t^T, the same from the stretch it comes with.
      EXPECT_NEAR(rotationOfTilt(tilt, d), 0.5 * (-d.y * tilt.x + d.x * tilt.y), 1e-15);
      EXPECT_NEAR(rotationOfSlope(a, b, d), rotationOfTilt(tilt, d), 1e-12) << d << tilt;
    }
  }
  EXPECT_EQ(tiltFromStretch(0.01, 0.02, cv::Point2d(0.0, 0.0)), cv::Point2d(0.0, 0.0));
}

// A straight flight of `frames` frames over flat ground at 20 m, 4.5 m (about 50 px) per frame.
sim::FlightPlan flatLine(int frames, unsigned seed) {
  sim::FlightOptions options;
  options.width = options.height = kN;
  options.flat = true;
  options.track.shape = sim::TrackShape::kLine;
  options.track.frames = frames;
  options.track.length = (frames - 1) * 4.5;
  options.track.altitude = 20.0;
  options.seed = seed;
  return sim::planFlight(options);
}

RegistrationConfig pairConfig() {
  RegistrationConfig config;
  config.size = kN;
  config.fft_planning = FftPlanning::kEstimate;
  return config;
}

// Two frames of a straight flight over flat ground (flatLine), their renderer and a registrar
// of the tests' size.
struct FlatPairRig {
  explicit FlatPairRig(unsigned seed)
      : plan(flatLine(2, seed)),
        renderer(std::make_shared<const sim::Scene>(plan.scene), plan.camera, 2),
        registrar(pairConfig()) {}
  const sim::FlightPlan plan;
  const sim::Renderer renderer;
  Registrar registrar;
};

// Two frames of a flight over flat ground whose camera is pitched and rolled by the same small
// angle in both (a levelled view whose attitude was off by it): the pair's zoom reads a change of
// altitude that is not there; the stretch the refinement fits reads the tilt, and the zoom
// corrected for it is one.
TEST(PlaneTilt, ALevelledViewOffByTheAttitudeErrorGetsItsZoomBack) {
  FlatPairRig rig(4);
  const sim::FlightPlan& plan = rig.plan;
  const sim::Renderer& renderer = rig.renderer;
  Registrar& registrar = rig.registrar;
  for (const double error : {0.0, 2.0 * kDeg}) {
    sim::FlightPose older = plan.poses[0], newer = plan.poses[1];
    older.pitch = newer.pitch = error;
    older.roll = newer.roll = -0.5 * error;
    const FrameSpectra a = registrar.analyse(renderer.render(older).image);
    const FrameSpectra b = registrar.analyse(renderer.render(newer).image);
    registrar.setPlaneTilt(cv::Point2d(0.0, 0.0));
    const PairRegistration plain = registrar.registerPair(a, b, RegistrationMethod::kEnergyVectors);
    ASSERT_TRUE(plain.zoom_refined) << error;
    const cv::Point2d read = tiltFromStretch(plain.stretch_a, plain.stretch_b, plain.translation);
    const double tilt = std::hypot(error, 0.5 * error) / plan.camera.intrinsics.fx;  // [1/px]
    // The tilt read is the attitude error's, in size and direction (pitch 2, roll -1: along
    // (2, -1) in the image, up to its sign), and the zoom misses 1.5 tilt.d (1.2 % here).
    EXPECT_NEAR(cv::norm(read), tilt, 0.05 * tilt + 5e-6) << error;
    EXPECT_NEAR(std::fabs(read.x + 2.0 * read.y), 0.0, 0.05 * tilt + 5e-6) << error;
    EXPECT_NEAR(std::log(plain.zoom), -logZoomOfTilt(read, plain.translation), 0.0012) << error;
    registrar.setPlaneTilt(read);
    const PairRegistration corrected = registrar.registerPair(a, b, RegistrationMethod::kEnergyVectors);
    ASSERT_TRUE(corrected.zoom_refined) << error;
    EXPECT_NEAR(std::log(corrected.zoom), 0.0, 0.0012) << error;
    if (error > 0.0) {
      EXPECT_GT(std::fabs(std::log(plain.zoom)), 0.004);
    }
    // Without a plane tilt set (a level camera) the same stretch is fitted; without a prediction
    // of the zoom nothing is corrected (ALevelFlightOverASlopeReadsNoClimb has one).
    registrar.setPlaneTilt(std::nullopt);
    const PairRegistration level = registrar.registerPair(a, b, RegistrationMethod::kEnergyVectors);
    ASSERT_TRUE(level.zoom_refined) << error;
    EXPECT_DOUBLE_EQ(level.stretch_a, plain.stretch_a) << error;
    EXPECT_DOUBLE_EQ(level.stretch_b, plain.stretch_b) << error;
    EXPECT_EQ(level.tilt_log_zoom, 0.0) << error;
    EXPECT_DOUBLE_EQ(level.zoom, plain.zoom) << error;
  }
}

// The same levelled view off by an attitude error, moving in several directions across the
// tilt: the pair reads a turn of half the tilt across the motion times its length although the
// camera did not turn (0.1-0.2 degrees here; every frame alike on a flight, so the heading drifts).
// The refinement's rotation holds all of it and, read with the stretch, gives the turn back; the
// surface's rotation holds a part of it, which the tracked tilt takes out.
TEST(PlaneTilt, ALevelledViewOffByTheAttitudeErrorReadsNoTurn) {
  FlatPairRig rig(4);
  double surface_before = 0.0, surface_after = 0.0;
  int cases = 0;
  for (const double yaw : {30.0, 60.0, 90.0, 150.0}) {
    for (const double error : {2.0 * kDeg, -2.0 * kDeg}) {
      sim::FlightPose older = rig.plan.poses[0], newer = rig.plan.poses[1];
      older.yaw += yaw * kDeg;
      newer.yaw += yaw * kDeg;
      older.pitch = newer.pitch = error;
      const FrameSpectra a = rig.registrar.analyse(rig.renderer.render(older).image);
      const FrameSpectra b = rig.registrar.analyse(rig.renderer.render(newer).image);
      rig.registrar.setPlaneTilt(std::nullopt);
      const PairRegistration level = rig.registrar.registerPair(a, b, RegistrationMethod::kEnergyVectors);
      ASSERT_TRUE(level.zoom_refined) << yaw << " " << error;
      const cv::Point2d d = level.translation;
      const cv::Point2d tilt = tiltFromStretch(level.stretch_a, level.stretch_b, d);
      const double turn = rotationOfTilt(tilt, d);
      EXPECT_GT(std::fabs(turn), 0.08 * kDeg) << yaw << " " << error;
      EXPECT_NEAR(level.refined_rotation, -turn, 0.15 * std::fabs(turn)) << yaw << " " << error;
      rig.registrar.setPlaneTilt(tilt);
      const PairRegistration levelled = rig.registrar.registerPair(a, b, RegistrationMethod::kEnergyVectors);
      ASSERT_TRUE(levelled.zoom_refined) << yaw << " " << error;
      EXPECT_NEAR(levelled.refined_rotation, 0.0, 0.01 * kDeg) << yaw << " " << error;
      EXPECT_GT(levelled.refined_rotation_sigma, level.refined_rotation_sigma) << "the stretch's error is in it";
      surface_before += std::fabs(level.rotation);
      surface_after += std::fabs(levelled.rotation);
      ++cases;
    }
  }
  EXPECT_LT(surface_after, 0.6 * surface_before) << "surface |rotation| summed over " << cases << " pairs";
}

TEST(PlaneTilt, TheSlopeCorrectionIsMinusTheStretchAlongTheMotion) {
  for (const cv::Point2d d : {cv::Point2d(80.0, 30.0), cv::Point2d(-12.0, 55.0), cv::Point2d(0.0, -40.0)}) {
    for (const cv::Point2d tilt : {cv::Point2d(3e-5, -2e-5), cv::Point2d(-1e-4, 0.0), cv::Point2d(0.0, 5e-5)}) {
      const auto [a, b] = stretchOf(tilt, d);
      const cv::Point2d u = d / cv::norm(d);
      const double along = a * (u.x * u.x - u.y * u.y) + 2.0 * b * u.x * u.y;  // u^T S u
      EXPECT_NEAR(logZoomOfSlope(a, b, d), -along, 1e-15) << d << tilt;
      EXPECT_NEAR(logZoomOfSlope(a, b, d), 0.5 * tilt.dot(d), 1e-15) << d << tilt;
    }
  }
  EXPECT_EQ(logZoomOfSlope(0.01, 0.02, cv::Point2d(0.0, 0.0)), 0.0);
}

// A camera pitched and rolled by 3 degrees that moves parallel to its image plane over flat
// ground sees exactly what a level camera flying level over a surface that slopes by 3.35
// degrees sees: the ground's distance changes under the motion, the camera's along its axis does
// not. The pair's read zoom holds half the slope's rise (about 0.6 % here). With the motion so far
// predicting no climb, the stretch along the motion takes it out; a prediction on the other side
// of the read zoom, or none, leaves the zoom as read, and one short of the truth stops it there.
// What the correction did not take is the zoom's uncertainty: the zoom's calibrated sigma then
// covers the error the slope left in it.
TEST(PlaneTilt, ALevelFlightOverASlopeReadsNoClimb) {
  FlatPairRig rig(5);
  const sim::FlightPlan& plan = rig.plan;
  const sim::Renderer& renderer = rig.renderer;
  Registrar& registrar = rig.registrar;
  sim::FlightPose older = plan.poses[0], newer = plan.poses[1];
  older.pitch = newer.pitch = 3.0 * kDeg;
  older.roll = newer.roll = -1.5 * kDeg;
  // The optical axis in the world: the motion is made perpendicular to it by a climb or descent.
  const cv::Matx33d rotation = sim::opticalToWorld(older);
  const cv::Vec3d axis(rotation(0, 2), rotation(1, 2), rotation(2, 2));
  cv::Vec3d motion = newer.position - older.position;
  motion[2] = -(axis[0] * motion[0] + axis[1] * motion[1]) / axis[2];
  newer.position = older.position + motion;
  ASSERT_GT(std::fabs(motion[2]), 0.1);
  const FrameSpectra a = registrar.analyse(renderer.render(older).image);
  const FrameSpectra b = registrar.analyse(renderer.render(newer).image);
  const auto registered = [&](std::optional<double> predicted_log_zoom) {
    if (!predicted_log_zoom) return registrar.registerPair(a, b, RegistrationMethod::kEnergyVectors);
    RegistrationPrior prior;
    prior.log_zoom = *predicted_log_zoom;
    prior.rotation_window = 0.1;
    prior.log_zoom_window = 0.05;
    return registrar.registerPair(a, b, RegistrationMethod::kEnergyVectors, nullptr, &prior);
  };
  const PairRegistration unpredicted = registered(std::nullopt);
  ASSERT_TRUE(unpredicted.zoom_refined);
  const double read = std::log(unpredicted.zoom);
  EXPECT_EQ(unpredicted.tilt_log_zoom, 0.0);
  EXPECT_GT(std::fabs(read), 0.004);
  // The slope the stretch reads: 3.35 degrees over the focal length.
  const cv::Point2d tilt = tiltFromStretch(unpredicted.stretch_a, unpredicted.stretch_b, unpredicted.translation);
  const double slope = std::tan(std::hypot(3.0, 1.5) * kDeg) / plan.camera.intrinsics.fx;
  EXPECT_NEAR(cv::norm(tilt), slope, 0.1 * slope);

  // Nothing was taken: the whole slope reading, which would have undone the read zoom.
  EXPECT_NEAR(unpredicted.slope_log_zoom_sigma, std::fabs(read), 0.0012);
  const UncertaintyConfig uncertainty;
  EXPECT_GT(detail::calibrated(unpredicted, uncertainty).log_zoom_sigma, std::fabs(read));

  const PairRegistration predicted = registered(0.0);
  ASSERT_TRUE(predicted.zoom_refined);
  EXPECT_NEAR(std::log(predicted.zoom), 0.0, 0.0012);
  EXPECT_GT(std::fabs(predicted.tilt_log_zoom), 0.004);
  EXPECT_LT(predicted.slope_log_zoom_sigma, 0.0012);

  const PairRegistration beyond = registered(2.0 * read);  // the prediction on the read zoom's side
  ASSERT_TRUE(beyond.zoom_refined);
  EXPECT_EQ(beyond.tilt_log_zoom, 0.0);
  EXPECT_DOUBLE_EQ(beyond.zoom, unpredicted.zoom);
  EXPECT_DOUBLE_EQ(beyond.slope_log_zoom_sigma, unpredicted.slope_log_zoom_sigma);

  const PairRegistration short_of_truth = registered(0.5 * read);
  ASSERT_TRUE(short_of_truth.zoom_refined);
  EXPECT_NEAR(std::log(short_of_truth.zoom), 0.5 * read, 1e-12);
  EXPECT_NEAR(short_of_truth.slope_log_zoom_sigma, 0.5 * std::fabs(read), 0.0012);
  EXPECT_GT(detail::calibrated(short_of_truth, uncertainty).log_zoom_sigma, 0.5 * std::fabs(read));
}

// A straight flight over flat ground whose levelled views are off by 1.5 degrees throughout (an
// attitude source's error): taken as level the zooms read a climb or descent of a third of the
// altitude over the 9 altitudes flown (1.5 x 1.5 deg x 9); told the frames were levelled
// (Estimator::setLevelled), the estimator reads the tilt from the pairs' stretch and keeps the
// altitude.
TEST(PlaneTilt, TheEstimatorTakesTheTiltOutOfLevelledFrames) {
  sim::FlightPlan plan = flatLine(40, 6);
  for (sim::FlightPose& pose : plan.poses) pose.pitch = 1.5 * kDeg;
  const auto scene = std::make_shared<const sim::Scene>(plan.scene);
  const sim::Renderer renderer(scene, plan.camera, 2);
  std::vector<cv::Mat1f> frames;
  for (const sim::FlightPose& pose : plan.poses) frames.push_back(renderer.render(pose).image);
  cv::Point2d tilt_read;
  const auto altitudeChange = [&](bool levelled) {
    EstimatorConfig config;
    config.registration.size = kN;
    config.registration.fft_planning = FftPlanning::kEstimate;
    config.working_fx = plan.camera.intrinsics.fx;
    Estimator estimator(config);
    for (std::size_t k = 0; k < frames.size(); ++k) {
      if (levelled) estimator.setLevelled();
      const std::optional<Estimate> e = estimator.push(frames[k], 0.2 * static_cast<double>(k));
      EXPECT_TRUE(e && (k == 0 || e->state == TrackingState::kTracking)) << k;
      if (e) tilt_read = e->plane_tilt;
    }
    return estimator.pose().z;  // in units of the first altitude
  };
  const double as_level = altitudeChange(false);
  EXPECT_EQ(tilt_read, cv::Point2d(0.0, 0.0));  // not levelled: nothing estimated
  const double levelled = altitudeChange(true);
  EXPECT_GT(std::fabs(as_level), 0.2);
  EXPECT_LT(std::fabs(levelled), 0.4 * std::fabs(as_level));
  // The estimate reports the tilt it corrected for: the 1.5 degrees of the attitude's error.
  EXPECT_NEAR(cv::norm(tilt_read), 1.5 * kDeg, 0.3 * kDeg);
}

// Readings of one tilt from pairs moving in turning directions, with noise and a fifth of them
// parallax outliers.
TEST(PlaneTiltTracker, ReadsATiltThroughNoiseAndOutliers) {
  const cv::Point2d truth(4e-5, -2.5e-5);
  std::mt19937 rng(5);
  std::normal_distribution<double> noise(0.0, 0.2);
  PlaneTiltTracker tracker;
  for (int i = 0; i < 40; ++i) {
    const double direction = 0.15 * i;
    const cv::Point2d d(60.0 * std::cos(direction), 60.0 * std::sin(direction));
    cv::Point2d tilt = truth + cv::Point2d(noise(rng), noise(rng)) * cv::norm(truth);
    if (i % 5 == 2) tilt = -6.0 * truth;  // an outlier
    const auto [a, b] = stretchOf(tilt, d);
    tracker.add(a, b, d);
    if (tracker.readings() < PlaneTiltTracker::kMinimumReadings) {
      EXPECT_EQ(tracker.tilt(), cv::Point2d(0.0, 0.0));
    }
  }
  EXPECT_EQ(tracker.readings(), PlaneTiltTracker::kReadings);
  EXPECT_NEAR(tracker.tilt().x, truth.x, 0.15 * cv::norm(truth));
  EXPECT_NEAR(tracker.tilt().y, truth.y, 0.15 * cv::norm(truth));
}

// A tilt that wanders steadily: the estimate is the newest tilt's (a median would be the window's
// middle, 15 readings behind).
TEST(PlaneTiltTracker, FollowsAWanderingTiltWithoutLag) {
  PlaneTiltTracker tracker;
  const cv::Point2d d(50.0, 20.0);
  cv::Point2d tilt;
  for (int i = 0; i < 50; ++i) {
    tilt = cv::Point2d(1e-6 * i, -5e-7 * i);
    const auto [a, b] = stretchOf(tilt, d);
    tracker.add(a, b, d);
  }
  EXPECT_NEAR(tracker.tilt().x, tilt.x, 1e-9);
  EXPECT_NEAR(tracker.tilt().y, tilt.y, 1e-9);
}

// A tracker holding just enough readings of one tilt, from pairs moving by d.
PlaneTiltTracker trackerReading(const cv::Point2d& tilt, const cv::Point2d& d) {
  PlaneTiltTracker tracker;
  for (std::size_t i = 0; i < PlaneTiltTracker::kMinimumReadings; ++i) {
    const auto [a, b] = stretchOf(tilt, d);
    tracker.add(a, b, d);
  }
  return tracker;
}

// The frames turn: the readings turn with them into the newest frame's axes.
TEST(PlaneTiltTracker, ReadingsTurnWithTheFrames) {
  const cv::Point2d d(40.0, -30.0), tilt(3e-5, 1e-5);
  PlaneTiltTracker tracker = trackerReading(tilt, d);
  const double rotation = 0.4;
  tracker.turn(rotation);
  const cv::Point2d turned(std::cos(rotation) * tilt.x + std::sin(rotation) * tilt.y,
                           -std::sin(rotation) * tilt.x + std::cos(rotation) * tilt.y);
  EXPECT_NEAR(tracker.tilt().x, turned.x, 1e-12);
  EXPECT_NEAR(tracker.tilt().y, turned.y, 1e-12);
  tracker.clear();
  EXPECT_EQ(tracker.tilt(), cv::Point2d(0.0, 0.0));
}

// Readings that say nothing are left out: no motion, a stretch or a turn that is not finite.
TEST(PlaneTiltTracker, ReadingsThatSayNothingAreLeftOut) {
  const cv::Point2d d(40.0, -30.0), tilt(3e-5, 1e-5);
  PlaneTiltTracker tracker = trackerReading(tilt, d);
  tracker.add(0.01, 0.02, cv::Point2d(0.0, 0.0));
  tracker.add(std::nan(""), 0.0, d);
  tracker.add(0.0, INFINITY, d);
  tracker.add(0.01, 0.0, cv::Point2d(std::nan(""), 1.0));
  tracker.turn(std::nan(""));
  EXPECT_EQ(tracker.readings(), PlaneTiltTracker::kMinimumReadings);
  EXPECT_NEAR(tracker.tilt().x, tilt.x, 1e-12);
  EXPECT_NEAR(tracker.tilt().y, tilt.y, 1e-12);
}

TEST(PlaneTiltTracker, ASmallChangeOfOneReadingMovesTheTiltALittle) {
  // A bag and a folder of the same flight round their attitudes differently: the tilt must not
  // flip where one reading crosses the outlier's threshold. The newest reading (the line's end
  // leans on it the most) sits where a cut at three robust sigmas would drop it; moved by 1e-9
  // either way, the tilt moves by as little.
  const auto tiltWithNewest = [](double newest) {
    PlaneTiltTracker tracker;
    // add(a, b, (1, 0)) reads the tilt (-2a, -2b) (tiltFromStretch).
    for (int k = 0; k < 29; ++k) tracker.add(-0.5 * (1e-4 * ((k * 7) % 11 - 5)), 0.0, {1.0, 0.0});
    tracker.add(-0.5 * newest, 0.0, {1.0, 0.0});
    return tracker.tilt().x;
  };
  // The 30 readings: median 1e-4, median absolute deviation 3e-4 (the newest one's 3 sigmas out).
  const double three_sigmas = 1e-4 + 3.0 * 1.4826 * 3e-4;
  const double below = tiltWithNewest(three_sigmas - 1e-9), above = tiltWithNewest(three_sigmas + 1e-9);
  EXPECT_LT(std::fabs(above - below), 1e-7);
  EXPECT_NE(below, 0.0);
}

}  // namespace
}  // namespace oefmt
