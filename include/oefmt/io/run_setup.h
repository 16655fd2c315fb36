// SPDX-License-Identifier: GPL-3.0-or-later
// What a run needs besides its frames, chosen the same way by oefmt_offline and the ROS node:
// the frames' camera (and so the working image's focal length) and the starting altitude. Both
// programs gather their inputs (files, options, messages, parameters) and ask these functions,
// so the same inputs give the same set-up, and doc/parameters.md's precedence holds for both.
#pragma once

#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "oefmt/io/dataset.h"

namespace oefmt {

/// Where the frames' camera can come from.
struct CameraSources {
  /// The calibration that comes with the frames (cam_param.yaml, a CameraInfo) and its name.
  std::optional<CameraParameters> calibration;
  std::string calibration_source;
  /// A focal length that replaces the calibration's, in the images' pixels (oefmt_offline --fx;
  /// 0 = none): it keeps the calibration's principal point and distortion.
  double override_fx = 0.0;
  std::string override_source;
  /// The configuration's camera_fx (0 = unset), used when nothing above gives a camera.
  double camera_fx = 0.0;
  /// False: the lens distortion is not undone (the frames are taken as already rectified).
  bool undistort = true;
};

/// The camera of the frames and the name of where it came from.
struct ChosenCamera {
  CameraParameters camera;
  std::string source;
};

/// The frames' camera for images of `image_size`, first that applies: the override focal length
/// (with the calibration's principal point mapped to the images, and its distortion), the
/// calibration, camera_fx as a pinhole; nullopt when none is known.
std::optional<ChosenCamera> chooseCamera(const CameraSources& sources, cv::Size image_size);

/// The starting altitude above the dominant plane [m], first that applies: a measurement or
/// an explicit choice for this run (the node's first Range, oefmt_offline --altitude), then the
/// configuration's initial_altitude. 0 = unknown (poses in units of the starting altitude).
double chooseInitialAltitude(std::optional<double> for_this_run, double configured);

}  // namespace oefmt
