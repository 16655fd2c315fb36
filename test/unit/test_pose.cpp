// SPDX-License-Identifier: GPL-3.0-or-later
// Pose accumulation (doc/method.md, Pose integration): signs, scale, yaw and covariance.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <sstream>
#include <string>

#include "oefmt/registration/registration.h"
#include "oefmt/estimation/pose.h"
#include "oefmt/io/tum.h"
#include "support/fixtures.h"
#include "support/flight_fixtures.h"

namespace oefmt {
namespace {

PairMotion step(double theta, double zoom, cv::Point2d d) {
  PairMotion m;
  m.rotation = theta;
  m.log_zoom = std::log(zoom);
  m.translation = d;
  m.rotation_sigma = 0.001;
  m.log_zoom_sigma = 0.002;
  m.translation_covariance = cv::Matx22d(0.25, 0.0, 0.0, 0.25);
  return m;
}

// Altitude 100 m seen with fx = 500 px: 0.2 m per pixel.
constexpr double kAltitude = 100.0;
constexpr double kFx = 500.0;

TEST(PoseIntegrator, ContentMovingRightMeansTheCameraFlewWest) {
  PoseIntegrator integrator(kAltitude, kFx);
  integrator.reset(0.0);
  const Pose4& p = integrator.integrate(step(0.0, 1.0, {10.0, 0.0}), 1.0);
  EXPECT_NEAR(p.x, -2.0, 1e-12);
  EXPECT_NEAR(p.y, 0.0, 1e-12);
  EXPECT_NEAR(p.z, 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(p.stamp, 1.0);
}

TEST(PoseIntegrator, ContentMovingDownMeansTheCameraFlewNorth) {
  PoseIntegrator integrator(kAltitude, kFx);
  integrator.reset(0.0);
  const Pose4& p = integrator.integrate(step(0.0, 1.0, {0.0, 10.0}), 1.0);
  EXPECT_NEAR(p.x, 0.0, 1e-12);
  EXPECT_NEAR(p.y, 2.0, 1e-12);
}

TEST(PoseIntegrator, ContentTurningCounterClockwiseMeansTheCameraYawedClockwise) {
  PoseIntegrator integrator(kAltitude, kFx);
  integrator.reset(0.0);
  EXPECT_NEAR(integrator.integrate(step(0.1, 1.0, {0.0, 0.0}), 1.0).yaw, -0.1, 1e-12);
}

TEST(PoseIntegrator, ShrinkingContentMeansClimbing) {
  PoseIntegrator integrator(kAltitude, kFx);
  integrator.reset(0.0);
  const Pose4& p = integrator.integrate(step(0.0, 1.0 / 1.1, {0.0, 0.0}), 1.0);
  EXPECT_NEAR(p.z, 10.0, 1e-9);
  EXPECT_NEAR(integrator.altitude(), 110.0, 1e-9);
  // At the new altitude a pixel covers more ground.
  EXPECT_NEAR(integrator.integrate(step(0.0, 1.0, {-10.0, 0.0}), 2.0).x, 10.0 * 110.0 / kFx, 1e-9);
}

// A restart whose first pair reads roofs at 80 % of the ground's depth: the pose stays where it
// is, the next steps' pixels cover 80 % as much ground, and a climb changes the roofs' depth by
// the same metres as the camera's height.
TEST(PoseIntegrator, AnotherReferencePlaneKeepsThePoseAndScalesTheSteps) {
  PoseIntegrator integrator(kAltitude, kFx);
  integrator.reset(0.0);
  integrator.integrate(step(0.0, 1.0, {-10.0, 0.0}), 1.0);
  const Pose4 before = integrator.pose();
  for (const double unusable : {0.0, -0.8, std::nan("")}) {
    integrator.moveReferencePlane(unusable);  // ignored: no plane lies there
    EXPECT_DOUBLE_EQ(integrator.altitude(), kAltitude) << unusable;
  }
  integrator.moveReferencePlane(0.8);
  EXPECT_DOUBLE_EQ(integrator.pose().x, before.x);
  EXPECT_DOUBLE_EQ(integrator.pose().z, before.z);
  EXPECT_NEAR(integrator.altitude(), 80.0, 1e-9);
  EXPECT_NEAR(integrator.integrate(step(0.0, 1.0, {-10.0, 0.0}), 2.0).x - before.x, 10.0 * 80.0 / kFx, 1e-9);
  const Pose4& climbed = integrator.integrate(step(0.0, 80.0 / 88.0, {0.0, 0.0}), 3.0);
  EXPECT_NEAR(climbed.z, 8.0, 1e-9);  // the camera's height, not the roofs' depth
  EXPECT_NEAR(integrator.altitude(), 88.0, 1e-9);
  integrator.reset(4.0);
  EXPECT_NEAR(integrator.altitude(), kAltitude, 1e-9);  // a reset goes back to the first plane
}

TEST(PoseIntegrator, ShiftsAreTurnedByTheHeading) {
  PoseIntegrator integrator(kAltitude, kFx);
  integrator.reset(0.0);
  // Yaw 90 degrees counter-clockwise (content turns clockwise), then the content moves right in
  // the new image: the camera flew towards its own left, which now is south.
  integrator.integrate(step(-CV_PI / 2, 1.0, {0.0, 0.0}), 1.0);
  const Pose4& p = integrator.integrate(step(0.0, 1.0, {10.0, 0.0}), 2.0);
  EXPECT_NEAR(p.yaw, CV_PI / 2, 1e-12);
  EXPECT_NEAR(p.x, 0.0, 1e-9);
  EXPECT_NEAR(p.y, -2.0, 1e-9);
}

TEST(PoseIntegrator, CovarianceGrowsAndStaysSymmetric) {
  PoseIntegrator integrator(kAltitude, kFx);
  integrator.reset(0.0);
  double previous_trace = 0.0;
  for (int k = 1; k <= 20; ++k) {
    const Pose4& p = integrator.integrate(step(0.01, 1.001, {8.0, -3.0}), k);
    ASSERT_TRUE(p.finite());
    const double trace = cv::trace(p.covariance);
    EXPECT_GT(trace, previous_trace);
    previous_trace = trace;
    for (int r = 0; r < 4; ++r) {
      EXPECT_GT(p.covariance(r, r), 0.0);
      for (int c = 0; c < 4; ++c) EXPECT_NEAR(p.covariance(r, c), p.covariance(c, r), 1e-12);
    }
  }
  // 20 independent heading errors of 1 mrad each.
  EXPECT_NEAR(std::sqrt(integrator.pose().covariance(3, 3)), 0.001 * std::sqrt(20.0), 1e-9);
}

TEST(PoseIntegrator, HoldKeepsThePoseAndInflatesTheCovariance) {
  PoseIntegrator integrator(kAltitude, kFx);
  integrator.reset(0.0);
  const Pose4 before = integrator.integrate(step(0.0, 1.0, {5.0, 0.0}), 1.0);
  const Pose4& held = integrator.hold(2.0, cv::Matx44d::eye() * 4.0);
  EXPECT_DOUBLE_EQ(held.x, before.x);
  EXPECT_DOUBLE_EQ(held.stamp, 2.0);
  EXPECT_NEAR(held.covariance(0, 0), before.covariance(0, 0) + 4.0, 1e-12);
}

TEST(PoseIntegrator, RejectsUnusableScale) {
  EXPECT_ANY_THROW(PoseIntegrator(0.0, kFx));
  EXPECT_ANY_THROW(PoseIntegrator(1.0, -1.0));
  EXPECT_ANY_THROW(PoseIntegrator(std::nan(""), kFx));
}

TEST(Pose, TumLinesAndQuaternions) {
  Pose4 pose;
  pose.stamp = 12.5;
  pose.x = 1.0;
  pose.y = -2.0;
  pose.z = 0.5;
  pose.yaw = CV_PI / 2;
  std::istringstream line(toTumLine(pose));
  double t, x, y, z, qx, qy, qz, qw;
  line >> t >> x >> y >> z >> qx >> qy >> qz >> qw;
  ASSERT_FALSE(line.fail());
  EXPECT_DOUBLE_EQ(t, 12.5);
  EXPECT_DOUBLE_EQ(y, -2.0);
  EXPECT_DOUBLE_EQ(qx, 0.0);
  EXPECT_NEAR(qz, std::sqrt(0.5), 1e-9);
  EXPECT_NEAR(qw, std::sqrt(0.5), 1e-9);
}

TEST(Pose, RosCovarianceLayout) {
  Pose4 pose;
  pose.covariance(0, 0) = 1.0;
  pose.covariance(0, 3) = pose.covariance(3, 0) = 0.5;
  pose.covariance(3, 3) = 2.0;
  const std::array<double, 36> c = covariance6x6(pose, 1e6, 1e-9);
  EXPECT_DOUBLE_EQ(c[0], 1.0);
  EXPECT_DOUBLE_EQ(c[0 * 6 + 5], 0.5);
  EXPECT_DOUBLE_EQ(c[5 * 6 + 0], 0.5);
  EXPECT_DOUBLE_EQ(c[5 * 6 + 5], 2.0);
  EXPECT_DOUBLE_EQ(c[3 * 6 + 3], 1e6);
  EXPECT_DOUBLE_EQ(c[2 * 6 + 2], 1e-9);  // never zero
}

// Rendered flight: registration + integration, checked against the camera's true path.
// World units are texture pixels (altitude = fx = n).
TEST(Pose, RenderedFlightHasTheRightDirectionYawAndScale) {
  constexpr int kN = 256;
  const double yaw_step = test::rad(1.5);
  const std::vector<test::CameraState> states = test::straightLine(12, 6.0, 4.0, yaw_step, 1.0);
  const test::Flight flight = test::renderFlight(test::flightTexture(), states, kN);
  Registrar registrar(test::sharedContext(kN));
  PoseIntegrator integrator(kN, kN);
  integrator.reset(0.0);
  FrameSpectra previous = registrar.analyse(flight.frames[0]);
  for (std::size_t k = 1; k < flight.frames.size(); ++k) {
    FrameSpectra current = registrar.analyse(flight.frames[k]);
    const PairRegistration r = registrar.registerPair(previous, current);
    ASSERT_TRUE(r.usable()) << k;
    integrator.integrate(PairMotion::fromRegistration(r), static_cast<double>(k));
    previous = std::move(current);
  }
  const test::CameraState& last = states.back();
  const Pose4& p = integrator.pose();
  const double travelled = std::hypot(last.east, last.north);
  EXPECT_NEAR(p.x, last.east, 0.01 * travelled);
  EXPECT_NEAR(p.y, last.north, 0.01 * travelled);
  // The registration's rotation is good to about 0.05 degrees per pair (and its zoom to 0.1 %) at
  // this size; 11 pairs add up.
  EXPECT_GT(p.yaw, 0.0) << "a counter-clockwise turn must give a positive yaw";
  EXPECT_NEAR(p.yaw, last.yaw, test::rad(0.6));
  EXPECT_NEAR(p.z, 0.0, 0.015 * kN);
}

TEST(Pose, RenderedClimbRaisesZ) {
  constexpr int kN = 256;
  const std::vector<test::CameraState> states = test::straightLine(8, 2.0, 0.0, 0.0, 1.03);
  const test::Flight flight = test::renderFlight(test::flightTexture(), states, kN);
  Registrar registrar(test::sharedContext(kN));
  PoseIntegrator integrator(1.0, kN);  // unknown altitude: units of the initial altitude
  integrator.reset(0.0);
  FrameSpectra previous = registrar.analyse(flight.frames[0]);
  for (std::size_t k = 1; k < flight.frames.size(); ++k) {
    FrameSpectra current = registrar.analyse(flight.frames[k]);
    integrator.integrate(PairMotion::fromRegistration(registrar.registerPair(previous, current)), k);
    previous = std::move(current);
  }
  const double expected_z = states.back().altitude - 1.0;  // about +0.23 initial altitudes
  EXPECT_GT(integrator.pose().z, 0.0);
  EXPECT_NEAR(integrator.pose().z, expected_z, 0.01);
}

}  // namespace
}  // namespace oefmt
