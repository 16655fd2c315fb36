// SPDX-License-Identifier: GPL-3.0-or-later
// The camera's attitude from an IMU, for attitude-aided registration: a tilted camera's frame is
// turned into the view of a virtual camera at the same place looking straight down, so that the
// tilt is never read as translation.
//
// The camera body is the optical frame turned 180 degrees about x (x image right, y image up, z
// against the view); level and looking straight down, its z is the world's up. Its attitude is
// yaw, pitch, roll about z, y', x'' (world <- body = Rz(yaw) Ry(pitch) Rx(roll)). The images give
// the yaw; the IMU gives pitch and roll, which are measured against gravity and need no compass.
#pragma once

#include <array>
#include <deque>
#include <optional>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace oefmt {

struct CameraTilt {
  double roll = 0.0;   ///< [rad]
  double pitch = 0.0;  ///< [rad]
};

/// Where the tilted camera's optical axis meets the virtual nadir camera's frame, relative to its
/// principal point [px], for a virtual camera of focal length `fx` [px]: the point a rangefinder
/// aligned with the camera reads. Zero for a level camera.
Eigen::Vector2d opticalAxisInNadirView(const CameraTilt& tilt, double fx);

/// The tilt of a camera whose optical frame turns into the world by `world_from_optical`.
CameraTilt cameraTilt(const Eigen::Matrix3d& world_from_optical);

/// The rotation from the tilted camera's optical frame to the virtual nadir camera's: the same
/// yaw, no tilt.
Eigen::Matrix3d nadirFromOptical(const CameraTilt& tilt);

/// The angle between a tilted camera's view and straight down [rad].
double tiltAngle(const CameraTilt& tilt);

/// A frame taken as level because its attitude is unknown (the IMU went quiet), of a vehicle
/// that tilts up to about `tilt_sigma` [rad]: its tilt is read as a shift of the position by up to
/// altitude * tan(tilt_sigma) in x and y (not a drift: a step between two such frames reads the
/// difference of their tilts, so the shift is undone once frames are levelled again), and its
/// roll and pitch are unknown within tilt_sigma. Adds both to `covariance`, a 6x6 pose covariance
/// (x y z roll pitch yaw, row-major, REP-103); `altitude` in the position's unit.
void addUnknownTilt(std::array<double, 36>& covariance, double altitude, double tilt_sigma);

/// The camera body's orientation (body to world) of a yaw and a tilt.
Eigen::Quaterniond cameraBodyOrientation(double yaw, const CameraTilt& tilt);

/// The camera body (x image right, y image up, z against the view) of a camera looking straight
/// down the body's -z axis: the optical frame's orientation in the body for cameraTiltAt.
Eigen::Matrix3d downLookingMount();

class AttitudeHistory;
/// The tilt at `stamp` of a camera mounted on the body at `body_from_optical`, from the body's
/// orientations; nothing when the history has none at that stamp.
std::optional<CameraTilt> cameraTiltAt(const AttitudeHistory& body, double stamp,
                                       const Eigen::Matrix3d& body_from_optical = downLookingMount());

/// Orientations of a body (body to world) over time, as an IMU or attitude filter gives them,
/// read at any stamp between two of them by spherical interpolation.
class AttitudeHistory {
 public:
  /// max_gap: two samples further apart than this [s] do not bracket a stamp (a gap in the data
  /// is no information about what happened in it).
  explicit AttitudeHistory(double max_gap = 0.1);

  /// Adds a sample; one not after the newest is ignored (returns false).
  bool add(double stamp, const Eigen::Quaterniond& body_to_world);
  /// The orientation at `stamp`: interpolated between the samples just before and after it, or
  /// a sample at it; nullopt when no pair within max_gap brackets it.
  std::optional<Eigen::Quaterniond> at(double stamp) const;
  /// Drops samples no longer needed for stamps from `stamp` on.
  void forgetBefore(double stamp);

  bool empty() const { return samples_.empty(); }
  double newestStamp() const { return samples_.empty() ? -1.0 : samples_.back().stamp; }

 private:
  struct Sample {
    double stamp;
    Eigen::Quaterniond orientation;
  };
  double max_gap_;
  std::deque<Sample> samples_;
};

/// How far a MEMS gyro's rate may be off, bias and noise together [rad/s] (about 0.6 deg/s: an
/// uncalibrated consumer gyro's bias): the uncertainty of a turn integrated from it is this times
/// the interval.
inline constexpr double kGyroRateError = 0.01;

/// A body's yaw turn over time, from its gyro: the rate of the yaw (of yaw, pitch, roll about z,
/// y', x'') from the angular velocity (body frame) and the orientation, integrated. For the camera
/// body of frames levelled to look straight down (the level view keeps the yaw), the turn between
/// two frames, which the gyro measures far better than the images' motion so far predicts it (a
/// sudden yaw, a texture that matches itself turned).
class TurnHistory {
 public:
  /// max_gap: samples further apart than this [s] do not cover the time between them;
  /// imu_from_body: the body whose yaw is wanted (a camera body) in the frame of the samples.
  explicit TurnHistory(double max_gap = 0.1, const Eigen::Matrix3d& imu_from_body = Eigen::Matrix3d::Identity());

  /// Adds a sample of the IMU (its orientation, to the world, and its angular velocity, in its
  /// frame); one not after the newest is ignored (returns false).
  bool add(double stamp, const Eigen::Quaterniond& imu_to_world, const Eigen::Vector3d& angular_velocity);
  /// The turn from `from` to `to` [rad, counter-clockwise seen from above]: the yaw rate
  /// integrated by trapezoids, linearly interpolated at both ends; nothing unless the samples
  /// cover [from, to] without a gap longer than max_gap.
  std::optional<double> turn(double from, double to) const;
  /// Drops samples no longer needed for turns from `stamp` on.
  void forgetBefore(double stamp);

  bool empty() const { return samples_.empty(); }

 private:
  struct Sample {
    double stamp;
    double rate;  // of the yaw [rad/s]
  };
  double max_gap_;
  Eigen::Matrix3d imu_from_body_;
  std::deque<Sample> samples_;
};

}  // namespace oefmt
