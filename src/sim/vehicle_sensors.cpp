// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/sim/vehicle_sensors.h"

#include <cmath>
#include <limits>
#include <random>

#include "oefmt/error.h"

namespace oefmt {
namespace sim {
namespace {

Eigen::Matrix3d toEigen(const cv::Matx33d& m) {
  Eigen::Matrix3d out;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) out(r, c) = m(r, c);
  }
  return out;
}

Eigen::Vector3d toEigen(const cv::Vec3d& v) { return {v[0], v[1], v[2]}; }

}  // namespace

void ImuOptions::validate() const {
  requireInput(std::isfinite(rate) && rate >= 1.0 && rate <= 2000.0, "imu: rate must be in [1, 2000] Hz");
  for (const double value : {gyro_noise, gyro_bias, accel_noise, attitude_error, orientation_noise}) {
    requireInput(std::isfinite(value) && value >= 0.0, "imu: noise, bias and errors must be >= 0");
  }
}

void RangeOptions::validate() const {
  requireInput(std::isfinite(noise) && noise >= 0.0, "range: noise must be >= 0");
  requireInput(dropout >= 0.0 && dropout < 1.0, "range: dropout must be in [0, 1)");
  requireInput(std::isfinite(max_range) && max_range > 0.0, "range: maximum range must be > 0");
}

std::vector<ImuSample> simulateImu(const VehicleMotion& motion, double t0, double t1, const ImuOptions& options,
                                   std::uint32_t seed) {
  options.validate();
  std::mt19937 random(seed ^ 0x1a4u);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0), angle(0.0, 2.0 * CV_PI);
  const Eigen::Vector3d bias(options.gyro_bias * uniform(random), options.gyro_bias * uniform(random),
                             options.gyro_bias * uniform(random));
  // The attitude filter's slow wander: one sine per axis, periods of 20-60 s.
  double period[2], phase[2];
  for (int axis = 0; axis < 2; ++axis) {
    period[axis] = 20.0 + 40.0 * (0.5 + 0.5 * uniform(random));
    phase[axis] = angle(random);
  }
  std::vector<ImuSample> samples;
  const double step = 1.0 / options.rate;
  for (long k = 0;; ++k) {
    const double t = t0 + k * step;
    if (t > t1 + 1e-9) break;
    ImuSample sample;
    sample.stamp = t;
    const Eigen::Quaterniond truth(toEigen(bodyToWorld(motion.poseAt(t))));
    const Eigen::Vector3d error(
        options.attitude_error * std::sin(2.0 * CV_PI * t / period[0] + phase[0]) + options.orientation_noise * normal(random),
        options.attitude_error * std::sin(2.0 * CV_PI * t / period[1] + phase[1]) + options.orientation_noise * normal(random),
        options.orientation_noise * normal(random));
    // The error as a small rotation in the body frame.
    sample.orientation = error.norm() > 0.0
                             ? (truth * Eigen::Quaterniond(Eigen::AngleAxisd(error.norm(), error.normalized()))).normalized()
                             : truth;
    sample.angular_velocity = toEigen(motion.angularVelocityAt(t)) + bias +
                              options.gyro_noise * Eigen::Vector3d(normal(random), normal(random), normal(random));
    sample.linear_acceleration = toEigen(motion.specificForceAt(t)) +
                                 options.accel_noise * Eigen::Vector3d(normal(random), normal(random), normal(random));
    samples.push_back(sample);
  }
  return samples;
}

double simulateRange(const Scene& scene, const FlightPose& pose, const RangeOptions& options, std::uint32_t seed,
                     int index) {
  options.validate();
  std::mt19937 random(seed * 2654435761u + static_cast<std::uint32_t>(index) * 40503u + 0x5a17u);
  std::uniform_real_distribution<double> uniform(0.0, 1.0);
  std::normal_distribution<double> normal(0.0, 1.0);
  const double drop = uniform(random);
  const double noise = options.noise * normal(random);
  const cv::Vec3d down = bodyToWorld(pose) * cv::Vec3d(0.0, 0.0, -1.0);
  if (!(down[2] < 0.0)) return std::numeric_limits<double>::infinity();
  const double distance = scene.cast(pose.position, down).t;  // `down` is a unit vector
  if (drop < options.dropout || !(distance <= options.max_range)) return std::numeric_limits<double>::infinity();
  return std::max(1e-3, distance + noise);
}

}  // namespace sim
}  // namespace oefmt
