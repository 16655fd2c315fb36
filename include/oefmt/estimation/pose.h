// SPDX-License-Identifier: GPL-3.0-or-later
// 4-DOF poses of the camera (x, y, z, yaw) accumulated from pair motions (doc/method.md,
// Pose integration).
#pragma once

#include <array>
#include <iosfwd>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/estimation/pair_motion.h"

namespace oefmt {

/// A camera pose in the world frame (REP-103, right-handed, z up). The world frame is the first
/// frame's footprint: x = right in the first image (east), y = up in the first image (north),
/// z = up; its origin is the first camera position. yaw turns the camera counter-clockwise seen
/// from above (0 = the first frame's heading). Units: metres when the initial altitude is known,
/// otherwise units of the initial altitude (initial altitude = 1).
struct Pose4 {
  double stamp = 0.0;  ///< [s]
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;      ///< height above the first camera position
  double yaw = 0.0;    ///< [rad], wrapped to (-pi, pi]
  /// Covariance of (x, y, z, yaw), first order from the pair sigmas; zero at the origin.
  cv::Matx44d covariance = cv::Matx44d::zeros();

  bool finite() const;
};

/// The pose with x, y, z times `factor` and their covariance times its square (a trajectory seen at
/// another scale).
Pose4 rescaled(const Pose4& pose, double factor);

/// The covariance as a row-major 6x6 over (x, y, z, roll, pitch, yaw), as nav_msgs/Odometry
/// wants it. Roll and pitch are not observed (the camera is assumed level): they get
/// `unobserved_variance`. Every diagonal entry is at least `min_variance` (never publish zeros).
std::array<double, 36> covariance6x6(const Pose4& pose, double unobserved_variance = 1e6,
                                     double min_variance = 1e-9);

/// Unit quaternion (qx, qy, qz, qw) of a rotation by yaw about z.
std::array<double, 4> yawQuaternion(double yaw);

/// Accumulates pair motions into poses: with psi the heading in the first image's
/// axes (psi = -yaw) and Z the altitude above the reference plane,
///   psi_k = wrap(psi_{k-1} + theta),  Z_k = Z_{k-1} / s,
///   step  = -(Z_k / fx) R(psi_k) d   in first-image axes (y down): the camera moves opposite to
///   the content, by the content shift scaled from pixels at altitude Z_k to world units;
/// the step's y is flipped into the world's y (north = up in the image), z = Z_k - Z_0 (plus the
/// height of a reference plane moveReferencePlane() moved: z stays the camera's height).
class PoseIntegrator {
 public:
  /// initial_altitude: Z_0 above the dominant plane in output units (the altitude in metres, or 1
  /// when unknown); fx: focal length in pixels of the working image. Throws InputError unless
  /// both are finite and > 0.
  PoseIntegrator(double initial_altitude, double fx);

  /// Back to the origin with zero covariance.
  void reset(double stamp);
  /// Adds the motion from the previous frame to this one; returns the new pose.
  const Pose4& integrate(const PairMotion& step, double stamp);
  /// Keeps the pose (no usable motion for this frame) and adds `extra_covariance`.
  const Pose4& hold(double stamp, const cv::Matx44d& extra_covariance);
  /// A measurement of the altitude above the reference plane (output units) with its variance:
  /// z moves toward it by the Kalman gain of z's own variance, which shrinks accordingly.
  void correctAltitude(double altitude, double variance);
  /// Goes back to an earlier pose (e.g. undoing predictions once the real motion is known).
  void restore(const Pose4& pose) { pose_ = pose; }
  /// Everything so far at another scale: the initial altitude and the position (x, y, z) times
  /// `factor` (> 0), their covariance times its square, as if the flight had started at
  /// factor times the initial altitude (every step's metres per pixel scale alike).
  void rescale(double factor);
  /// The steps from here follow another plane, `depth_ratio` (> 0) times as deep below the camera
  /// as the current reference plane (a restart whose first pair read another depth layer): the
  /// pose stays, and the next steps' metres per pixel and altitude change scale with the new
  /// plane's depth.
  void moveReferencePlane(double depth_ratio);
  /// The covariance the last integrate() or hold() added to the pose (x, y, z, yaw): the
  /// uncertainty of that one step alone, in the world frame and output units.
  const cv::Matx44d& lastStepCovariance() const { return last_step_covariance_; }

  const Pose4& pose() const { return pose_; }
  /// Z_k: current altitude above the reference plane (output units).
  double altitude() const { return initial_altitude_ + pose_.z - plane_height_; }
  double initialAltitude() const { return initial_altitude_; }
  double fx() const { return fx_; }

 private:
  double initial_altitude_;
  double fx_;
  // How far the reference plane lies above the first frame's (output units): z stays the
  // camera's height when moveReferencePlane() changes the plane.
  double plane_height_ = 0.0;
  Pose4 pose_;
  cv::Matx44d last_step_covariance_ = cv::Matx44d::zeros();
};

}  // namespace oefmt
