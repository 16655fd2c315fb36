// SPDX-License-Identifier: GPL-3.0-or-later
// oefmt_node: the same OdometryRos as the nodelet, in a process of its own.
#include <exception>

#include <ros/ros.h>

#include "oefmt/ros/odometry_ros.h"

int main(int argc, char** argv) {
  ros::init(argc, argv, "oefmt");
  try {
    oefmt::OdometryRos odometry(ros::NodeHandle(), ros::NodeHandle("~"), ros::this_node::getName());
    ros::spin();
  } catch (const std::exception& e) {
    ROS_FATAL_STREAM(ros::this_node::getName() << ": " << e.what());
    return 1;
  }
  return 0;
}
