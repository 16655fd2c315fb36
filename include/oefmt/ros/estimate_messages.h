// SPDX-License-Identifier: GPL-3.0-or-later
// Estimates as ROS messages (odometry, TF, energy vectors) and the debug plots rviz shows.
#pragma once

#include <string>

#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <opencv2/core.hpp>
#include <std_msgs/Header.h>

#include "oefmt/EnergyVectors.h"
#include "oefmt/estimation/estimator.h"

namespace oefmt {

/// Odometry of `pose` in header.frame_id with child_frame: pose and covariance; the twist (in
/// child_frame) from the difference to `previous` (none: zero twist with a large covariance).
/// Covariances are never zero; roll and pitch are reported unobserved.
nav_msgs::Odometry odometryMessage(const Pose4& pose, const Pose4* previous,
                                   const std_msgs::Header& header, const std::string& child_frame);

/// The pose of a base frame mounted at yaw `mount_yaw` from the camera body (x = image right),
/// in an odom frame aligned with that base at the start: position and x-y covariance turned by
/// mount_yaw about z, yaw unchanged. The lever arm between camera and base is ignored.
Pose4 rotatedPose(const Pose4& pose, double mount_yaw);

/// TF of a pose: header.frame_id -> child_frame.
geometry_msgs::TransformStamped transformMessage(const Pose4& pose, const std_msgs::Header& header,
                                                 const std::string& child_frame);

/// The newest pair's energy vectors, matching factors, sigmas and optimizer report.
oefmt::EnergyVectors energyVectorsMessage(const Estimate& estimate, double log_zoom_per_bin,
                                          double shift_per_bin, const std_msgs::Header& header);

/// BGR plot of the zoom (S) and translation (T) energy vectors of pairs 1-2 and 0-2 with the
/// matching factors, for rviz's Image display.
cv::Mat renderEnergyVectors(const Estimate& estimate, double shift_per_bin, cv::Size size = {800, 500});

/// A correlation surface as a BGR heat map: inferno colour of cbrt(|v| / max|v|) (cube-root
/// scaled so that weak peaks show; 0 is black). NaN pixels take the top colour.
cv::Mat renderSurface(const cv::Mat1f& surface);

}  // namespace oefmt
