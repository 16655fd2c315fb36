// SPDX-License-Identifier: GPL-3.0-or-later
// The simulated multirotor: level unless asked, leaning into its acceleration as physics wants,
// an IMU whose readings agree with the motion (angular velocity, specific force, orientation),
// and a rangefinder that reads the distance to the surface below along the body's down axis.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <memory>

#include <opencv2/calib3d.hpp>

#include "oefmt/error.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/vehicle_motion.h"
#include "oefmt/sim/vehicle_sensors.h"

namespace oefmt {
namespace sim {
namespace {

constexpr double kDeg = CV_PI / 180.0;

TrackConfig circle(double length = 491.0, int frames = 200, double altitude = 20.0) {
  TrackConfig track;
  track.shape = TrackShape::kCircle;
  track.length = length;
  track.frames = frames;
  track.altitude = altitude;
  return track;
}

TEST(VehicleMotion, LevelUnlessTiltIsAsked) {
  const VehicleMotion motion(circle(), 5.0, 1.0, TiltOptions{}, 3);
  for (double t = 1.0; t < 40.0; t += 3.7) {
    const FlightPose pose = motion.poseAt(t);
    EXPECT_TRUE(pose.level());
  }
  // The frames' poses are the track's own.
  const std::vector<FlightPose> frames = makeTrack(circle());
  for (int k = 0; k < 199; k += 17) {
    const FlightPose pose = motion.poseAt(1.0 + k / 5.0);
    EXPECT_NEAR(cv::norm(pose.position - frames[k].position), 0.0, 1e-9) << k;
  }
}

TEST(VehicleMotion, LeansIntoTheCentripetalAcceleration) {
  // A circle of radius R flown at speed v: acceleration v^2 / R towards the centre.
  const TrackConfig track = circle();
  const double rate = 5.0, speed = frameSpacing(track) * rate, radius = track.length / (2.0 * CV_PI);
  const double expected = std::atan(speed * speed / radius / kGravity);
  TiltOptions tilt;
  tilt.follow_acceleration = true;
  const VehicleMotion motion(track, rate, 1.0, tilt, 3);
  for (double t = 2.0; t < 38.0; t += 4.1) {
    const FlightPose pose = motion.poseAt(t);
    const cv::Matx33d body = bodyToWorld(pose);
    // The body's up axis leans towards the centre by atan(a / g).
    const cv::Vec3d up(body(0, 2), body(1, 2), body(2, 2));
    const cv::Vec3d inward = -cv::Vec3d(pose.position[0], pose.position[1], 0.0) * (1.0 / radius);
    EXPECT_NEAR(std::acos(up[2]), expected, 0.2 * kDeg) << t;
    EXPECT_GT(up.dot(inward), 0.0) << t;
    // Level and steady in the body: the accelerometer reads only the thrust, along +z.
    const cv::Vec3d force = motion.specificForceAt(t);
    EXPECT_NEAR(force[0], 0.0, 0.02) << t;
    EXPECT_NEAR(force[1], 0.0, 0.02) << t;
    EXPECT_NEAR(force[2], std::hypot(kGravity, speed * speed / radius), 0.02) << t;
  }
}

TEST(VehicleMotion, WobbleStaysWithinItsAmplitudeAndTheClamp) {
  TiltOptions tilt;
  tilt.wobble = 8.0 * kDeg;
  tilt.wobble_frequency = 1.0;
  const VehicleMotion motion(circle(), 5.0, 1.0, tilt, 9);
  double largest = 0.0;
  for (double t = 1.0; t < 40.0; t += 0.05) {
    const FlightPose pose = motion.poseAt(t);
    largest = std::max({largest, std::fabs(pose.roll), std::fabs(pose.pitch)});
  }
  EXPECT_LE(largest, 8.0 * kDeg + 1e-12);
  EXPECT_GT(largest, 4.0 * kDeg);  // it does wobble
  tilt.follow_acceleration = true;
  tilt.max_tilt = 5.0 * kDeg;
  const VehicleMotion clamped(circle(), 5.0, 1.0, tilt, 9);
  for (double t = 1.0; t < 40.0; t += 0.5) {
    const FlightPose pose = clamped.poseAt(t);
    EXPECT_LE(std::hypot(pose.roll, pose.pitch), 5.0 * kDeg + 1e-12);
  }
  tilt.wobble = -1.0;
  EXPECT_THROW(VehicleMotion(circle(), 5.0, 1.0, tilt, 9), InputError);
}

TEST(VehicleMotion, AngularVelocityIsTheRotationsRate) {
  TrackConfig spin;
  spin.shape = TrackShape::kSpin;
  spin.frames = 50;
  spin.altitude = 20.0;
  spin.spin_rate = 6.0 * kDeg;
  const VehicleMotion motion(spin, 5.0, 1.0, TiltOptions{}, 1);
  const cv::Vec3d w = motion.angularVelocityAt(3.3);
  EXPECT_NEAR(w[0], 0.0, 1e-6);
  EXPECT_NEAR(w[1], 0.0, 1e-6);
  EXPECT_NEAR(w[2], 6.0 * kDeg * 5.0, 1e-6);
  // With wobble: integrating the body rates reproduces the change of orientation.
  TiltOptions tilt;
  tilt.wobble = 6.0 * kDeg;
  tilt.follow_acceleration = true;
  const VehicleMotion wobbling(circle(), 5.0, 1.0, tilt, 4);
  cv::Matx33d integrated = bodyToWorld(wobbling.poseAt(5.0));
  const double dt = 1e-3;
  for (double t = 5.0; t < 6.0 - 1e-9; t += dt) {
    cv::Matx33d step;
    cv::Rodrigues(wobbling.angularVelocityAt(t + dt / 2) * dt, step);
    integrated = integrated * step;
  }
  cv::Vec3d error;
  cv::Rodrigues(integrated.t() * bodyToWorld(wobbling.poseAt(6.0)), error);
  EXPECT_LT(cv::norm(error), 0.05 * kDeg);
}

TEST(VehicleSensors, ImuAgreesWithTheMotionWithinItsNoise) {
  TiltOptions tilt;
  tilt.follow_acceleration = true;
  tilt.wobble = 5.0 * kDeg;
  const VehicleMotion motion(circle(), 5.0, 1.0, tilt, 6);
  ImuOptions options;
  const std::vector<ImuSample> samples = simulateImu(motion, 1.0, 11.0, options, 6);
  ASSERT_EQ(samples.size(), 2001u);  // 200 Hz over 10 s, both ends
  double worst_attitude = 0.0, gyro_error = 0.0, force_error = 0.0;
  for (const ImuSample& s : samples) {
    const cv::Matx33d truth = bodyToWorld(motion.poseAt(s.stamp));
    Eigen::Matrix3d r = s.orientation.toRotationMatrix();
    cv::Matx33d measured;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) measured(i, j) = r(i, j);
    }
    cv::Vec3d error;
    cv::Rodrigues(truth.t() * measured, error);
    worst_attitude = std::max(worst_attitude, cv::norm(error));
    const cv::Vec3d w = motion.angularVelocityAt(s.stamp), f = motion.specificForceAt(s.stamp);
    gyro_error += (s.angular_velocity - Eigen::Vector3d(w[0], w[1], w[2])).squaredNorm();
    force_error += (s.linear_acceleration - Eigen::Vector3d(f[0], f[1], f[2])).squaredNorm();
  }
  EXPECT_LT(worst_attitude, options.attitude_error * std::sqrt(2.0) + 5.0 * options.orientation_noise);
  EXPECT_GT(worst_attitude, 0.3 * options.attitude_error);  // the error is there
  // Per axis: noise^2 + bias^2 (bias uniform in [-b, b]) at most.
  const double gyro_rms = std::sqrt(gyro_error / samples.size() / 3.0);
  EXPECT_LT(gyro_rms, std::hypot(options.gyro_noise, options.gyro_bias) * 1.3);
  EXPECT_NEAR(std::sqrt(force_error / samples.size() / 3.0), options.accel_noise, 0.2 * options.accel_noise);
}

TEST(VehicleSensors, RangeIsTheDistanceAlongTheBodysDownAxis) {
  SceneConfig config;
  config.seed = 2;
  config.region = cv::Rect2d(-50, -50, 100, 100);
  config.texture_size = 64;
  config.texel = 1.0;
  config.cell_size = 5.0;
  config.feature_texels = 8.0;
  config.levels.clear();  // flat ground
  const Scene scene(config);
  RangeOptions exact;
  exact.noise = 0.0;
  exact.dropout = 0.0;
  FlightPose pose;
  pose.position = cv::Vec3d(1.0, 2.0, 20.0);
  EXPECT_NEAR(simulateRange(scene, pose, exact, 1, 0), 20.0, 1e-9);
  pose.roll = 10.0 * kDeg;
  pose.pitch = -5.0 * kDeg;
  EXPECT_NEAR(simulateRange(scene, pose, exact, 1, 0), 20.0 / (std::cos(10.0 * kDeg) * std::cos(5.0 * kDeg)), 1e-9);
  exact.max_range = 15.0;
  EXPECT_TRUE(std::isinf(simulateRange(scene, pose, exact, 1, 0)));
  // Dropouts at their rate, as +inf.
  RangeOptions noisy;
  noisy.dropout = 0.2;
  int dropped = 0;
  for (int k = 0; k < 1000; ++k) dropped += std::isinf(simulateRange(scene, pose, noisy, 1, k)) ? 1 : 0;
  EXPECT_NEAR(dropped, 200, 50);
}

TEST(TiltedFlight, LevelOptionsLeaveTheFlightAsItWasAndTiltShowsInTheGroundTruth) {
  FlightOptions options;
  options.width = options.height = 128;
  options.track.frames = 20;
  options.track.length = 100.0;
  const FlightPlan level = planFlight(options);
  options.tilt.follow_acceleration = true;
  options.tilt.wobble = 4.0 * kDeg;
  const FlightPlan tilted = planFlight(options);
  ASSERT_EQ(level.poses.size(), tilted.poses.size());
  for (std::size_t k = 0; k < level.poses.size(); ++k) {
    EXPECT_TRUE(level.poses[k].level());
    EXPECT_EQ(level.poses[k].position, tilted.poses[k].position);
    EXPECT_EQ(level.poses[k].yaw, tilted.poses[k].yaw);
    EXPECT_FALSE(tilted.poses[k].level());
  }
  const std::vector<ImuSample> imu = simulateFlightImu(tilted);
  EXPECT_NEAR(imu.front().stamp, tilted.stamps.front(), 1e-12);
  EXPECT_NEAR(imu.back().stamp, tilted.stamps.back(), 1e-9);
}

}  // namespace
}  // namespace sim
}  // namespace oefmt
