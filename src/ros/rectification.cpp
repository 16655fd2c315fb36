// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/ros/rectification.h"

#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"
#include "oefmt/ros/bag_io.h"

namespace oefmt {

sensor_msgs::CameraInfo workingFrameInfo(const Undistorter& undistorter) {
  if (!undistorter.remaps()) throw InputError("no lens distortion to undo: no working frame to rectify");
  const Intrinsics& out = undistorter.intrinsics();
  // The source camera's K and lens, the working frame's size and projection.
  // (Any valid stamp: the header is cleared, the working frame belongs to no message.)
  sensor_msgs::CameraInfo info = cameraInfoMessage(undistorter.sourceCamera(), 1.0, "");
  info.header = std_msgs::Header();
  info.width = static_cast<std::uint32_t>(out.width);
  info.height = static_cast<std::uint32_t>(out.height);
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
