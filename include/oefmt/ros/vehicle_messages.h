// SPDX-License-Identifier: GPL-3.0-or-later
// The vehicle's IMU and downward rangefinder as ROS messages (sensor_msgs/Imu, sensor_msgs/Range,
// REP-117 for readings without return), read from and written to bags.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include <geometry_msgs/TransformStamped.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/Range.h>

#include "oefmt/io/vehicle_data.h"

namespace oefmt {

/// Standard deviations an IMU message's covariances are filled from.
struct ImuNoise {
  double orientation = 0.3 * M_PI / 180.0;  ///< [rad]
  double angular_velocity = 0.005;          ///< [rad/s]
  double linear_acceleration = 0.05;        ///< [m/s^2]
};

sensor_msgs::Imu imuMessage(const ImuSample& sample, const std::string& frame_id, const ImuNoise& noise = {});
/// The sample of a message (its header stamp). A message without orientation (covariance[0] = -1,
/// as sensor_msgs/Imu has it) gives the identity; check hasOrientation first. One without angular
/// velocity (its covariance[0] = -1) gives NaN rates.
ImuSample imuSample(const sensor_msgs::Imu& message);
bool hasOrientation(const sensor_msgs::Imu& message);

/// A downward rangefinder's reading: range +inf (no return) stays +inf, as REP-117 wants.
sensor_msgs::Range rangeMessage(const RangeSample& sample, const std::string& frame_id, double max_range = 60.0);
/// The reading of a message: +inf for no return (+inf, or above max_range), nothing-like -inf kept
/// as -inf (too close), NaN as +inf (invalid).
RangeSample rangeSample(const sensor_msgs::Range& message);

/// The IMU samples (those with an orientation) and range readings of two topics of a bag, in
/// time order (empty topic: none).
/// Throws BagError naming the bag and topic when it cannot be read or a topic holds another type.
std::vector<ImuSample> readImuTopic(const std::string& bag_path, const std::string& topic);
std::vector<RangeSample> readRangeTopic(const std::string& bag_path, const std::string& topic);

/// The frame id of the first sensor_msgs/Imu, Image, CompressedImage or Range message on `topic`
/// of a bag; empty when it has none. Throws BagError when the bag cannot be read.
std::string firstFrameId(const std::string& bag_path, const std::string& topic);

/// The rotation of frame `source` in frame `target` (target <- source) from a bag's /tf_static,
/// chained through their common frames; nothing when those transforms do not connect them
/// (`why` then says what is missing). Throws BagError when the bag cannot be read.
std::optional<Eigen::Quaterniond> staticRotation(const std::string& bag_path, const std::string& target,
                                                 const std::string& source, std::string& why);

/// A static transform parent -> child (rotation as a quaternion x, y, z, w).
geometry_msgs::TransformStamped staticTransform(const std::string& parent, const std::string& child, double stamp,
                                                double qx, double qy, double qz, double qw);

}  // namespace oefmt
