// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/sim/vehicle_motion.h"

#include <cmath>
#include <random>

#include <opencv2/calib3d.hpp>

#include "oefmt/error.h"

namespace oefmt {
namespace sim {
namespace {

// Time steps of the finite differences [s]: the acceleration over a window long against the
// track's arc table (so that its linear pieces do not show) and short against any manoeuvre; the
// angular velocity over a much shorter one.
constexpr double kAccelerationStep = 0.05;
constexpr double kRotationStep = 1e-3;

// The rotation vector (axis times angle) of a rotation matrix.
cv::Vec3d rotationVector(const cv::Matx33d& r) {
  cv::Vec3d vector;
  cv::Rodrigues(r, vector);
  return vector;
}

}  // namespace

void TiltOptions::validate() const {
  requireInput(std::isfinite(wobble) && wobble >= 0.0 && wobble <= CV_PI / 6.0, "tilt: wobble must be in [0, 30] deg");
  requireInput(std::isfinite(wobble_frequency) && wobble_frequency > 0.0 && wobble_frequency <= 20.0,
               "tilt: wobble frequency must be in (0, 20] Hz");
  requireInput(std::isfinite(max_tilt) && max_tilt > 0.0 && max_tilt <= CV_PI / 4.0,
               "tilt: the maximum tilt must be in (0, 45] deg");
}

VehicleMotion::VehicleMotion(const TrackConfig& track, double rate, double start_time, const TiltOptions& tilt,
                             std::uint32_t seed)
    : path_(track), rate_(rate), start_time_(start_time), tilt_(tilt) {
  requireInput(std::isfinite(rate) && rate > 0.0, "motion: the frame rate must be > 0");
  tilt_.validate();
  // The wobble's own generator: the flight's other random choices are unchanged by it.
  std::mt19937 random(seed ^ 0x7e11u);
  std::uniform_real_distribution<double> fraction(0.4, 1.0), angle(0.0, 2.0 * CV_PI);
  for (int axis = 0; axis < 2; ++axis) {
    for (int k = 0; k < 2; ++k) {
      frequency_[axis][k] = tilt_.wobble_frequency * (k == 0 ? 1.0 : fraction(random));
      phase_[axis][k] = angle(random);
    }
  }
}

cv::Vec3d VehicleMotion::positionAt(double t) const { return path_.at((t - start_time_) * rate_).position; }

double VehicleMotion::wobble(double t, int axis) const {
  // Weights 0.6 + 0.4: the sum stays within the amplitude.
  return tilt_.wobble * (0.6 * std::sin(2.0 * CV_PI * frequency_[axis][0] * t + phase_[axis][0]) +
                         0.4 * std::sin(2.0 * CV_PI * frequency_[axis][1] * t + phase_[axis][1]));
}

cv::Vec3d VehicleMotion::accelerationAt(double t) const {
  const double h = kAccelerationStep;
  return (positionAt(t + h) - 2.0 * positionAt(t) + positionAt(t - h)) * (1.0 / (h * h));
}

FlightPose VehicleMotion::poseAt(double t) const {
  FlightPose pose = path_.at((t - start_time_) * rate_);
  if (!tilt_.any()) return pose;
  double pitch = wobble(t, 1), roll = wobble(t, 0);
  if (tilt_.follow_acceleration) {
    // Thrust along the body's z axis supplies a - g: z_body is parallel to (a_x, a_y, g). In the
    // yawed frame, Ry(pitch) Rx(roll) e_z = (cos r sin p, -sin r, cos r cos p).
    const cv::Vec3d a = accelerationAt(t);
    const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
    const double forward = c * a[0] + s * a[1], left = -s * a[0] + c * a[1];
    const double up = kGravity + a[2];
    pitch += std::atan2(forward, up);
    roll += std::atan2(-left, std::hypot(forward, up));
  }
  const double tilt = std::hypot(pitch, roll);
  if (tilt > tilt_.max_tilt) {
    pitch *= tilt_.max_tilt / tilt;
    roll *= tilt_.max_tilt / tilt;
  }
  pose.pitch = pitch;
  pose.roll = roll;
  return pose;
}

cv::Vec3d VehicleMotion::angularVelocityAt(double t) const {
  const double h = kRotationStep;
  const cv::Matx33d before = bodyToWorld(poseAt(t - h)), after = bodyToWorld(poseAt(t + h));
  return rotationVector(before.t() * after) * (1.0 / (2.0 * h));
}

cv::Vec3d VehicleMotion::specificForceAt(double t) const {
  const cv::Vec3d force = accelerationAt(t) + cv::Vec3d(0.0, 0.0, kGravity);
  return bodyToWorld(poseAt(t)).t() * force;
}

}  // namespace sim
}  // namespace oefmt
