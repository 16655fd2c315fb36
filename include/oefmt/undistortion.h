// SPDX-License-Identifier: GPL-3.0-or-later
// The camera of the frames as the estimator sees them: a calibration made for another resolution
// is mapped onto the images, and lens distortion is undone before registration. One setup for
// oefmt_offline (cam_param.yaml, a bag's CameraInfo) and the node (camera_info), so that both
// register the same frames.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/dataset.h"
#include "oefmt/image_prep.h"

namespace oefmt {

/// One line saying how a calibration of another resolution is applied to images of
/// `image_size` (intrinsicsForImageSize: a centred crop to their aspect, resized), naming
/// `source` ("cam_param.yaml", "camera_info"); empty when the calibration is of the images' size
/// or gives no size. Throws InputError for invalid intrinsics.
std::string describeSizeMapping(const Intrinsics& calibration, cv::Size image_size,
                                const std::string& source);

/// What a bare focal length (oefmt_offline --fx, the node's ~camera_fx) stands for: a pinhole
/// with fx = fy = `fx` for images of `image_size`, the principal point at their centre.
CameraParameters pinholeCamera(double fx, cv::Size image_size);

/// True when both calibrations are exactly the same (intrinsics, their size, distortion).
bool sameCamera(const CameraParameters& a, const CameraParameters& b);

/// Removes lens distortion from frames of one size. The undistorted frame has the input's size,
/// square pixels (fx = fy) and the principal point at its centre. Its focal length is the lens's
/// (the geometric mean of fx and fy), larger only when that is needed for every pixel to come
/// from inside the input image (pincushion lenses, an off-centre principal point): no invalid
/// (constant) border or corner, which would stay put in every frame and correlate as a static
/// pattern. It is never made smaller (a wider view would shrink the centre, and registration
/// loses its finest texture to that blur: a barrel lens fits at its own focal length). Bicubic
/// interpolation for the same reason: bilinear blurs enough to change which depth layer
/// dominates a multi-depth scene, which shows as scale drift.
/// Without distortion nothing is resampled: apply() returns the frame as it is and intrinsics()
/// are the input's (the calibration mapped to the images' size).
class Undistorter {
 public:
  /// `camera`: the calibration, for images of camera.intrinsics.width x height (0: the images'
  /// own size), mapped to `image_size` by intrinsicsForImageSize; `source` names it in messages
  /// ("cam_param.yaml", "camera_info"). Throws InputError, in one line naming `source`, for
  /// invalid intrinsics, a non-finite coefficient, or a distortion that cannot be undone over
  /// the image: one that folds it over (not invertible), puts the principal point outside it, or
  /// leaves less than half of its field of view (absurd coefficients, or another lens's).
  Undistorter(const CameraParameters& camera, cv::Size image_size,
              const std::string& source = "the calibration");

  /// True when this was set up from `camera` (as given to the constructor) for `image_size`.
  bool madeFor(const CameraParameters& camera, cv::Size image_size) const {
    return image_size == image_size_ && sameCamera(camera, calibration_);
  }
  /// True when frames are resampled (the distortion is not zero).
  bool remaps() const { return !map_xy_.empty(); }
  cv::Size imageSize() const { return image_size_; }
  /// The calibration mapped to the images' size (before undistortion).
  const CameraParameters& inputCamera() const { return input_; }
  /// Intrinsics of the frames apply() returns.
  const Intrinsics& intrinsics() const { return output_; }
  /// Focal length [px] of the working image the core makes of these frames (a centred square
  /// resized to size x size): the `fx` of EstimatorConfig.
  double workingFx(int size) const;

  /// The frame undistorted (any type cv::remap takes: 8/16-bit, float; 1, 3 or 4 channels), or
  /// `image` itself when remaps() is false. Throws InputError when remapping a frame of another
  /// size than imageSize(). Thread-safe.
  cv::Mat apply(const cv::Mat& image) const;

  /// What to tell the user, one line each: how a calibration of another resolution is mapped
  /// (describeSizeMapping) and what is undistorted (describe()); empty when neither applies.
  std::vector<std::string> notes() const;
  /// One line: what is undone and the intrinsics of the result.
  std::string describe() const;

 private:
  void setUp();

  cv::Size image_size_;
  std::string source_;
  CameraParameters calibration_;  // as given
  CameraParameters input_;
  Intrinsics output_;
  double kept_width_ = 1.0;  // horizontal field of view kept, fraction of the input's
  cv::Mat map_xy_, map_fraction_;  // fixed-point maps (cv::convertMaps)
};

}  // namespace oefmt
