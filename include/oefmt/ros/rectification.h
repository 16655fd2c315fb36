// SPDX-License-Identifier: GPL-3.0-or-later
// The node's working frames, rectified by image_geometry. The core's Undistorter decides what the
// estimator registers (the working frame's camera, as for oefmt_offline); image_geometry's camera
// model, set up from a CameraInfo of that frame, makes and keeps the rectification maps and
// resamples the frames.
#pragma once

#include <image_geometry/pinhole_camera_model.h>
#include <opencv2/core.hpp>
#include <sensor_msgs/CameraInfo.h>

#include "oefmt/io/undistortion.h"

namespace oefmt {

/// The CameraInfo of `undistorter`'s working frame (undistorter.remaps() must be true): K and D
/// of the frame it is resampled from (Undistorter::sourceCamera), R = I, P the working frame's
/// intrinsics, width x height the working frame's. (image_geometry makes rectified images of the
/// CameraInfo's size, from a raw image of any size: here Undistorter::sourceFrame.)
sensor_msgs::CameraInfo workingFrameInfo(const Undistorter& undistorter);

/// The frame the estimator registers: `undistorter`'s working frame of `image`, remapped by
/// `camera` (set up from workingFrameInfo(undistorter)) with bicubic interpolation, as
/// Undistorter::apply makes it; `image` itself when undistorter.remaps() is false. Throws
/// InputError as Undistorter::apply does.
cv::Mat rectifyToWorkingFrame(const Undistorter& undistorter, const image_geometry::PinholeCameraModel& camera,
                              const cv::Mat& image);

}  // namespace oefmt
