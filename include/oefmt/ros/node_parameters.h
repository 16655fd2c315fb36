// SPDX-License-Identifier: GPL-3.0-or-later
// The ROS node's own parameters (frames, topics, queues, diagnostics) and their table. The
// estimator's parameters (estimatorParameters) share the node's private namespace. No ROS
// headers: the documentation generator reads this table too.
#pragma once

#include <string>

#include "oefmt/estimation/parameter_table.h"

namespace oefmt {

/// Parameters that only the ROS wrapper has; nodeParameters() describes each.
struct RosParameters {
  std::string odom_frame = "odom";
  std::string base_frame = "base_link";
  std::string camera_frame;          ///< empty: the image header's frame_id
  bool publish_tf = true;
  bool compressed = false;           ///< subscribe to image/compressed instead of image
  int queue_size = 2;                ///< subscriber queue of image, camera_info
  int input_buffer = 1;              ///< frames waiting for the worker (1: the newest wins)
  int path_length = 2000;            ///< poses kept in the published path (0 = no path)
  /// Undo the lens distortion camera_info gives (false: the images are already rectified, or
  /// camera_info's D belongs to another lens than the one that took them).
  bool undistort = true;
  /// Take the initial altitude from the `altitude` Range topic (over initial_altitude).
  bool use_altitude_topic = false;
  /// Level every frame with the `imu` topic's roll and pitch whenever it publishes.
  bool use_imu = true;
  double imu_timeout = 0.1;          ///< [s] an IMU orientation further than this from a frame is stale
  /// Keep the scale metric with every valid `altitude` range (off until the node's use of the
  /// readings matches oefmt_offline's accuracy).
  bool use_range = true;
  double time_jump_tolerance = 1.0;  ///< a stamp this far back [s] resets (bag loop)
  double diagnostics_period = 1.0;   ///< [s]
  double min_rate = 1.0;             ///< expected input/output rate window [Hz] for diagnostics
  double max_rate = 100.0;

  /// Throws InputError naming the first invalid parameter.
  void validate() const;
};

/// The node's parameters (~name), bound to `parameters`' fields. Made for a default
/// RosParameters, its values are the defaults.
ParameterTable nodeParameters(RosParameters& parameters);

}  // namespace oefmt
