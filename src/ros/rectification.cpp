// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/ros/rectification.h"

#include <opencv2/imgproc.hpp>
#include <sensor_msgs/distortion_models.h>

#include "oefmt/error.h"

namespace oefmt {

sensor_msgs::CameraInfo workingFrameInfo(const Undistorter& undistorter) {
  if (!undistorter.remaps()) throw InputError("no lens distortion to undo: no working frame to rectify");
  const Intrinsics& k = undistorter.sourceCamera().intrinsics;
  const Distortion& d = undistorter.sourceCamera().distortion;
  const Intrinsics& out = undistorter.intrinsics();
  sensor_msgs::CameraInfo info;
  info.width = static_cast<std::uint32_t>(out.width);
  info.height = static_cast<std::uint32_t>(out.height);
  if (d.rational()) {
    info.distortion_model = sensor_msgs::distortion_models::RATIONAL_POLYNOMIAL;
    info.D = {d.k1, d.k2, d.p1, d.p2, d.k3, d.k4, d.k5, d.k6};
  } else {
    info.distortion_model = sensor_msgs::distortion_models::PLUMB_BOB;
    info.D = {d.k1, d.k2, d.p1, d.p2, d.k3};
  }
  info.K = {k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0};
  info.R = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  info.P = {out.fx, 0.0, out.cx, 0.0, 0.0, out.fy, out.cy, 0.0, 0.0, 0.0, 1.0, 0.0};
  return info;
}

cv::Mat rectifyToWorkingFrame(const Undistorter& undistorter, const image_geometry::PinholeCameraModel& camera,
                              const cv::Mat& image) {
  if (!undistorter.remaps()) return image;
  cv::Mat working;
  camera.rectifyImage(undistorter.sourceFrame(image), working, cv::INTER_CUBIC);
  return working;
}

}  // namespace oefmt
