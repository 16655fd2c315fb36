// SPDX-License-Identifier: GPL-3.0-or-later
// How a multirotor without gimbal flies a track: it leans into its horizontal acceleration
// (atan(a / g), as thrust along the body's up axis must supply it) and wobbles a little, so the
// rigidly mounted camera tilts with it. Continuous in time, so that an IMU can be sampled
// between the frames.
#pragma once

#include <cstdint>

#include <opencv2/core.hpp>

#include "oefmt/sim/camera_model.h"
#include "oefmt/sim/track.h"

namespace oefmt {
namespace sim {

constexpr double kGravity = 9.80665;  ///< [m/s^2]

struct TiltOptions {
  bool follow_acceleration = false;  ///< lean into the horizontal acceleration
  double wobble = 0.0;               ///< amplitude of a seeded smooth wobble of roll and pitch [rad]
  double wobble_frequency = 0.5;     ///< its highest frequency [Hz]
  double max_tilt = 25.0 * CV_PI / 180.0;  ///< the tilt (roll and pitch together) is clamped to this [rad]

  bool any() const { return follow_acceleration || wobble > 0.0; }
  /// Throws InputError naming the first invalid field.
  void validate() const;
};

class VehicleMotion {
 public:
  /// Frame k of `track` is flown at start_time + k / rate. Throws InputError for invalid options.
  VehicleMotion(const TrackConfig& track, double rate, double start_time, const TiltOptions& tilt,
                std::uint32_t seed);

  /// The body's pose at time t [s]: the track's position and yaw, the tilt's pitch and roll.
  FlightPose poseAt(double t) const;
  /// Acceleration of the body in the world [m/s^2] (gravity not included).
  cv::Vec3d accelerationAt(double t) const;
  /// Angular velocity of the body, in the body frame [rad/s].
  cv::Vec3d angularVelocityAt(double t) const;
  /// What an accelerometer on the body measures: the body's acceleration minus gravity, in the
  /// body frame [m/s^2] (level and still: +g on z).
  cv::Vec3d specificForceAt(double t) const;

 private:
  cv::Vec3d positionAt(double t) const;
  double wobble(double t, int axis) const;

  TrackPath path_;
  double rate_;
  double start_time_;
  TiltOptions tilt_;
  // Two sines per axis (roll, pitch): frequencies [Hz] and phases [rad], drawn from the seed.
  double frequency_[2][2] = {};
  double phase_[2][2] = {};
};

}  // namespace sim
}  // namespace oefmt
