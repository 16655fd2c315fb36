// SPDX-License-Identifier: GPL-3.0-or-later
// Attitude-aided registration: the camera's tilt read from its orientation, interpolation of an
// IMU's orientations between samples, and the claim it rests on: a pure roll or pitch between
// two frames over flat ground, once both frames are turned into the level view, registers as no
// translation (while the raw frames register as tens of pixels of it).
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>

#include "oefmt/estimation/attitude.h"
#include "oefmt/io/nadir_view.h"
#include "oefmt/registration/registration.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/renderer.h"
#include "support/fixtures.h"

namespace oefmt {
namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Matrix3d opticalOf(const Eigen::Quaterniond& body) { return body.toRotationMatrix() * downLookingMount(); }

TEST(Attitude, TiltComesBackFromTheOrientationWhateverTheYaw) {
  for (const double yaw : {0.0, 1.0, -2.5, 3.0}) {
    for (const CameraTilt tilt : {CameraTilt{0.0, 0.0}, CameraTilt{0.1, -0.2}, CameraTilt{-0.3, 0.05}}) {
      const CameraTilt back = cameraTilt(opticalOf(cameraBodyOrientation(yaw, tilt)));
      EXPECT_NEAR(back.roll, tilt.roll, 1e-12);
      EXPECT_NEAR(back.pitch, tilt.pitch, 1e-12);
    }
  }
  // Level: the nadir rotation is the identity.
  EXPECT_TRUE(nadirFromOptical(CameraTilt{}).isApprox(Eigen::Matrix3d::Identity(), 1e-15));
  // The nadir rotation takes the tilted optical axis to the level one: straight down.
  const double yaw = 0.7;
  const CameraTilt tilt{0.2, -0.1};
  const Eigen::Matrix3d optical = opticalOf(cameraBodyOrientation(yaw, tilt));
  const Eigen::Matrix3d virtual_optical = optical * nadirFromOptical(tilt).transpose();
  EXPECT_TRUE(virtual_optical.col(2).isApprox(Eigen::Vector3d(0.0, 0.0, -1.0), 1e-12));
}

TEST(Attitude, TiltAngleIsTheViewsAngleFromStraightDown) {
  EXPECT_NEAR(tiltAngle(CameraTilt{0.2, 0.0}), 0.2, 1e-12);
  EXPECT_NEAR(tiltAngle(CameraTilt{0.0, -0.3}), 0.3, 1e-12);
  // Roll then pitch: the view's z is (cos p cos r) down.
  EXPECT_NEAR(tiltAngle(CameraTilt{0.1, 0.2}), std::acos(std::cos(0.1) * std::cos(0.2)), 1e-12);
  EXPECT_EQ(tiltAngle(CameraTilt{}), 0.0);
  // Nothing added without a tilt to fear, or with a meaningless one.
  std::array<double, 36> covariance{};
  addUnknownTilt(covariance, 20.0, 0.0);
  addUnknownTilt(covariance, std::nan(""), 0.1);
  for (const double c : covariance) EXPECT_EQ(c, 0.0);
}

TEST(Attitude, HistoryInterpolatesBetweenSamplesAndNotAcrossGaps) {
  AttitudeHistory history(0.1);
  const Eigen::Quaterniond a(Eigen::AngleAxisd(0.0, Eigen::Vector3d::UnitX()));
  const Eigen::Quaterniond b(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX()));
  EXPECT_TRUE(history.add(1.0, a));
  EXPECT_TRUE(history.add(1.05, b));
  EXPECT_FALSE(history.add(1.05, a));  // not after the newest
  EXPECT_TRUE(history.add(1.5, a));    // after a gap
  const auto middle = history.at(1.025);
  ASSERT_TRUE(middle.has_value());
  EXPECT_NEAR(Eigen::AngleAxisd(*middle).angle(), 0.05, 1e-12);
  EXPECT_TRUE(history.at(1.05).has_value());
  EXPECT_FALSE(history.at(0.99).has_value());  // before the first
  EXPECT_FALSE(history.at(1.3).has_value());   // in the gap
  EXPECT_FALSE(history.at(1.6).has_value());   // after the newest
  history.forgetBefore(1.5);
  EXPECT_TRUE(history.at(1.5).has_value());
  // A camera's tilt from the body's orientation and the camera's mount: a mount turned 10 degrees
  // about the body's y adds 10 degrees of pitch.
  AttitudeHistory level;
  level.add(0.0, Eigen::Quaterniond::Identity());
  level.add(0.05, Eigen::Quaterniond::Identity());
  EXPECT_NEAR(cameraTiltAt(level, 0.02)->pitch, 0.0, 1e-12);
  const Eigen::Matrix3d mount = Eigen::AngleAxisd(0.1745, Eigen::Vector3d::UnitY()).toRotationMatrix() * downLookingMount();
  EXPECT_NEAR(cameraTiltAt(level, 0.02, mount)->pitch, 0.1745, 1e-9);
  EXPECT_FALSE(cameraTiltAt(level, 0.2).has_value());
}

TEST(AttitudeAidedRegistration, PureRollOrPitchRegistersAsNoTranslation) {
  constexpr int kN = 256;
  sim::FlightOptions options;
  options.width = options.height = kN;
  options.flat = true;
  options.track.frames = 2;
  options.track.length = 1.0;
  options.track.altitude = 20.0;
  options.seed = 3;
  const sim::FlightPlan plan = sim::planFlight(options);
  const auto scene = std::make_shared<const sim::Scene>(plan.scene);
  const sim::Renderer renderer(scene, plan.camera, 2);
  const NadirView nadir(plan.camera, cv::Size(kN, kN), plan.camera.intrinsics.fx, kN);
  Registrar registrar(test::sharedContext(kN));

  sim::FlightPose level = plan.poses[0];
  const cv::Mat1f level_view = nadir.apply(renderer.render(level).image, nadirFromOptical(CameraTilt{}));
  const FrameSpectra reference = registrar.analyse(level_view);
  for (const CameraTilt tilt : {CameraTilt{6.0 * kDeg, 0.0}, CameraTilt{0.0, -5.0 * kDeg}, CameraTilt{4.0 * kDeg, 3.0 * kDeg}}) {
    sim::FlightPose tilted = level;
    tilted.roll = tilt.roll;
    tilted.pitch = tilt.pitch;
    const cv::Mat1f raw = renderer.render(tilted).image;
    const PairRegistration unaided = registrar.registerPair(reference, registrar.analyse(raw));
    const PairRegistration aided =
        registrar.registerPair(reference, registrar.analyse(nadir.apply(raw, nadirFromOptical(tilt))));
    // Unaided, the tilt is seen as a shift of about f tan(tilt): 19-23 px here.
    const double seen_as_shift = plan.camera.intrinsics.fx * std::tan(std::hypot(tilt.roll, tilt.pitch));
    EXPECT_NEAR(cv::norm(unaided.translation), seen_as_shift, 0.15 * seen_as_shift) << tilt.roll << " " << tilt.pitch;
    // A frame the node must take as level (its IMU went quiet) carries that shift in its
    // position's covariance: per axis, one sigma of a tilt as large as this one reaches it.
    std::array<double, 36> covariance{};
    addUnknownTilt(covariance, options.track.altitude, tiltAngle(tilt));
    const double metres_per_px = options.track.altitude / plan.camera.intrinsics.fx;
    EXPECT_NEAR(std::hypot(unaided.translation.x, unaided.translation.y) * metres_per_px,
                std::sqrt(covariance[0]), 0.15 * std::sqrt(covariance[0]));
    EXPECT_LE(std::fabs(unaided.translation.x) * metres_per_px, 1.15 * std::sqrt(covariance[0]));
    EXPECT_LE(std::fabs(unaided.translation.y) * metres_per_px, 1.15 * std::sqrt(covariance[7]));
    EXPECT_DOUBLE_EQ(covariance[3 * 6 + 3], tiltAngle(tilt) * tiltAngle(tilt));
    EXPECT_DOUBLE_EQ(covariance[4 * 6 + 4], tiltAngle(tilt) * tiltAngle(tilt));
    EXPECT_DOUBLE_EQ(covariance[2 * 6 + 2], 0.0);  // the altitude is not what a tilt changes
    EXPECT_LT(cv::norm(aided.translation), 0.5) << tilt.roll << " " << tilt.pitch;
    EXPECT_NEAR(aided.rotation, 0.0, 0.2 * kDeg);
    EXPECT_NEAR(aided.zoom, 1.0, 0.003);
  }
}

}  // namespace
}  // namespace oefmt
