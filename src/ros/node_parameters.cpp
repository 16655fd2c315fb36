// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/ros/node_parameters.h"

#include "oefmt/error.h"

namespace oefmt {
namespace {

bool validFrameName(const std::string& frame) {
  return !frame.empty() && frame[0] != '/' && frame.find(' ') == std::string::npos;
}

constexpr const char* kFrameRule = "a frame name: not empty, no leading '/', no blank";

}  // namespace

ParameterTable nodeParameters(RosParameters& p) {
  ParameterTable table = {
      textParameter("odom_frame", p.odom_frame, "frame of the published pose"),
      textParameter("base_frame", p.base_frame, "child frame of the odometry"),
      textParameter("camera_frame", p.camera_frame,
                    "camera frame for the TF mount lookup (its yaw turns the odometry into "
                    "base_frame's axes); empty: the image's frame_id"),
      booleanParameter("publish_tf", p.publish_tf,
                       "broadcast odom_frame -> base_frame (false when another node publishes it)"),
      booleanParameter("compressed", p.compressed, "subscribe to image/compressed instead of image"),
      integerParameter("queue_size", p.queue_size, "messages", closedRange(1, 100),
                       "subscriber queues of the image and camera_info"),
      integerParameter("input_buffer", p.input_buffer, "frames", closedRange(1, 100),
                       "frames waiting for the worker thread: 1 = the newest wins (live camera); more "
                       "absorbs processing hiccups without drops (bag replay) at the cost of latency"),
      integerParameter("path_length", p.path_length, "poses", atLeast(0),
                       "poses kept in the published path; 0 = no path"),
      booleanParameter("undistort", p.undistort,
                       "undo camera_info's lens distortion; false when the images are already "
                       "rectified or camera_info's D belongs to another lens"),
      booleanParameter("use_altitude_topic", p.use_altitude_topic,
                       "take the initial altitude from the first valid range on the altitude topic "
                       "(sensor_msgs/Range; the odometry waits for it), over initial_altitude"),
      booleanParameter("use_imu", p.use_imu,
                       "level every frame with the roll and pitch of the imu topic (sensor_msgs/Imu with "
                       "an orientation; its frame taken as base_frame) whenever it publishes"),
      numberParameter("imu_timeout", p.imu_timeout, "s", above(0.0),
                      "an IMU orientation further than this from a frame's stamp is stale: the frame is "
                      "taken as level, with a warning"),
      booleanParameter("use_range", p.use_range,
                       "keep the scale metric with every valid range of the altitude topic (a downward "
                       "rangefinder, sensor_msgs/Range) whenever it publishes: the first 20 frames' readings "
                       "vote which depth layer they saw and the odometry so far is rescaled once by it (a "
                       "jump), later readings correct the altitude; false: its first reading only"),
      numberParameter("time_jump_tolerance", p.time_jump_tolerance, "s", above(0.0),
                      "a stamp this far behind the last one restarts the odometry; less is a dropped "
                      "reordering"),
      numberParameter("diagnostics_period", p.diagnostics_period, "s", above(0.0),
                      "period of /diagnostics"),
      numberParameter("min_rate", p.min_rate, "Hz", above(0.0),
                      "lowest expected input and output rate (rate diagnostics)"),
      numberParameter("max_rate", p.max_rate, "Hz", above(0.0),
                      "highest expected input and output rate (rate diagnostics)"),
  };
  for (Parameter& parameter : table) {
    if (parameter.key == "odom_frame") parameter.extra_rule = kFrameRule;
    if (parameter.key == "base_frame") parameter.extra_rule = std::string(kFrameRule) + ", not odom_frame";
    if (parameter.key == "camera_frame") parameter.extra_rule = "empty or a frame name";
    if (parameter.key == "max_rate") parameter.extra_rule = ">= min_rate";
  }
  return table;
}

void RosParameters::validate() const {
  RosParameters copy = *this;
  checkParameters(nodeParameters(copy));
  if (!validFrameName(odom_frame)) throwInvalidParameter("odom_frame", std::string("must be ") + kFrameRule);
  if (!validFrameName(base_frame)) throwInvalidParameter("base_frame", std::string("must be ") + kFrameRule);
  if (odom_frame == base_frame) throwInvalidParameter("base_frame", "must differ from odom_frame");
  if (!camera_frame.empty() && !validFrameName(camera_frame)) {
    throwInvalidParameter("camera_frame", std::string("must be empty or ") + kFrameRule);
  }
  if (max_rate < min_rate) throwInvalidParameter("max_rate", "must be >= min_rate");
}

}  // namespace oefmt
