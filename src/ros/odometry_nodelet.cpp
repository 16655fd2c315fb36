// SPDX-License-Identifier: GPL-3.0-or-later
// oefmt/OdometryNodelet: the odometry in a nodelet manager (zero-copy images from a camera
// driver nodelet). All the work is in OdometryRos.
#include <memory>

#include <nodelet/nodelet.h>
#include <pluginlib/class_list_macros.hpp>

#include "oefmt/ros/odometry_ros.h"

namespace oefmt {

class OdometryNodelet : public nodelet::Nodelet {
 private:
  void onInit() override {
    odometry_ = std::make_unique<OdometryRos>(getNodeHandle(), getPrivateNodeHandle(), getName());
  }
  std::unique_ptr<OdometryRos> odometry_;
};

}  // namespace oefmt

PLUGINLIB_EXPORT_CLASS(oefmt::OdometryNodelet, nodelet::Nodelet)
