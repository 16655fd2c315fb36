// SPDX-License-Identifier: GPL-3.0-or-later
// Attitude-aided registration's image side: a tilted camera's frame resampled into the working
// frame of a virtual camera at the same place, with the same yaw, looking straight down (the
// homography K' R K^-1 of a pure rotation, lens distortion undone in the same step). The
// estimator then sees what a level camera would have seen, and reads no tilt as translation.
#pragma once

#include <opencv2/core.hpp>

#include <Eigen/Core>

#include "oefmt/io/dataset.h"
#include "oefmt/registration/image_prep.h"

namespace oefmt {

class NadirView {
 public:
  /// `camera`: the calibration mapped to the frames' size `image_size`; the virtual camera has
  /// focal length `working_fx` [px] (the estimator's working_fx) and its principal point at the
  /// centre of its working_size x working_size frame. Throws InputError for invalid intrinsics or
  /// sizes.
  NadirView(const CameraParameters& camera, cv::Size image_size, double working_fx, int working_size);

  /// The virtual camera's grey float frame (working_size square) of `image`, whose optical frame
  /// turns into the virtual camera's by `nadir_from_optical` (nadirFromOptical()). What the real
  /// camera did not see is the mean of what it saw, the texture fading into it over working_size
  /// / 16 pixels. Throws InputError for a frame of another size or type toGreyFloat refuses, or
  /// one tilted so far that it saw nothing of the level view. Thread-safe.
  cv::Mat1f apply(const cv::Mat& image, const Eigen::Matrix3d& nadir_from_optical,
                  ChannelOrder order = ChannelOrder::kBgr) const;

  /// apply()'s view as the estimator takes it (prepareImage at working_size), with the mask of
  /// the pixels the camera saw (PreparedImage::seen: neither filled in nor faded; empty when the
  /// camera saw all of the view). Throws as apply().
  PreparedImage prepare(const cv::Mat& image, const Eigen::Matrix3d& nadir_from_optical,
                        ChannelOrder order = ChannelOrder::kBgr) const;

 private:
  CameraParameters source_camera_;  // the camera of the (shrunk) grey frame
  cv::Size image_size_;
  double shrink_ = 1.0;             // frames are shrunk by this first when much larger
  cv::Matx33d virtual_camera_;
  int working_size_;
  double fade_px_ = 32.0;           // the unseen part's ramp [px]

  // apply(); `seen` (when given) receives the mask prepare() describes.
  cv::Mat1f render(const cv::Mat& image, const Eigen::Matrix3d& nadir_from_optical, ChannelOrder order,
                   cv::Mat1b* seen) const;
};

}  // namespace oefmt
