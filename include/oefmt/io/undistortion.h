// SPDX-License-Identifier: GPL-3.0-or-later
// The camera of the frames as the estimator sees them: a calibration made for another resolution
// is mapped onto the images, and lens distortion is undone before registration. One setup for
// oefmt_offline (cam_param.yaml, a bag's CameraInfo) and the node (camera_info), so that both
// register the same frames.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/io/dataset.h"
#include "oefmt/registration/image_prep.h"

namespace oefmt {

/// One line saying how a calibration of another resolution is applied to images of
/// `image_size` (intrinsicsForImageSize: a centred crop to their aspect, resized), naming
/// `source` ("cam_param.yaml", "camera_info"); empty when the calibration is of the images' size
/// or gives no size. Throws InputError for invalid intrinsics.
std::string describeSizeMapping(const Intrinsics& calibration, cv::Size image_size,
                                const std::string& source);

/// What a bare focal length (oefmt_offline --fx, the parameter camera_fx) stands for: a pinhole
/// with fx = fy = `fx` for images of `image_size`, the principal point at their centre.
CameraParameters pinholeCamera(double fx, cv::Size image_size);

/// True when both calibrations are exactly the same (intrinsics, their size, distortion).
bool sameCamera(const CameraParameters& a, const CameraParameters& b);

/// Removes lens distortion from frames of one size, making the working frame the core registers:
/// the centred square of the undistorted view, working_size x working_size, grey float (as
/// toGreyFloat: integer images scaled to [0, 1]), square pixels (fx = fy) and the principal point
/// at its centre. prepareImage then has nothing left to crop or resize, and only the part of the
/// frame that is used is converted and resampled (a 4056 x 3040 frame is shrunk by area
/// interpolation first, as prepareImage would, then remapped at the working size).
/// Its focal length is the lens's at the working scale (the geometric mean of fx and fy, times
/// working_size / min(width, height)), larger only when that is needed for every pixel to come
/// from inside the frame (pincushion lenses, an off-centre principal point): no invalid
/// (constant) border or corner, which would stay put in every frame and correlate as a static
/// pattern. It is never made smaller: a wider view would shrink the centre, and registration
/// loses its finest texture to that blur (a barrel lens fits at its own scale). Bicubic
/// interpolation for the same reason: bilinear blurs enough to change which depth layer
/// dominates a multi-depth scene, which shows as scale drift.
/// Without distortion nothing is resampled: apply() returns the frame as it is and intrinsics()
/// are the input's (the calibration mapped to the images' size).
class Undistorter {
 public:
  /// `camera`: the calibration, for images of camera.intrinsics.width x height (0: the images'
  /// own size), mapped to `image_size` by intrinsicsForImageSize; `working_size`: the side of the
  /// estimator's working image (registration.size); `source` names the calibration in messages
  /// ("cam_param.yaml", "camera_info"). Throws InputError, in one line naming `source`, for
  /// invalid intrinsics, a non-finite coefficient, or a distortion that cannot be undone over
  /// the image: one that folds it over (not invertible), puts the principal point outside it, or
  /// leaves less than half of its field of view (absurd coefficients, or another lens's).
  Undistorter(const CameraParameters& camera, cv::Size image_size, int working_size,
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
  /// Intrinsics of the frames apply() returns: the working frame's when remaps(), else the
  /// input's.
  const Intrinsics& intrinsics() const { return output_; }
  /// Focal length [px] of the working image the core makes of apply()'s frames (a centred square
  /// resized to working_size): the `fx` of EstimatorConfig.
  double workingFx() const { return working_fx_; }

  /// The working frame (see the class), or `image` itself when remaps() is false. Any 1/3/4
  /// channel 8/16-bit or float frame (toGreyFloat's, in `order`). Throws InputError when
  /// remapping a frame of another size than imageSize() or one too small to register
  /// (requireRegistrableSize). Thread-safe.
  cv::Mat apply(const cv::Mat& image, ChannelOrder order = ChannelOrder::kBgr) const;

  /// For a remap done elsewhere (the ROS node's, by image_geometry): the frame apply() resamples,
  /// i.e. the part of `image` the working frame samples, grey float as apply() converts it and
  /// shrunk alike, with a border of kSourceMargin pixels replicated around it (the bicubic
  /// kernel's reach, so that a remap needs no border mode). Only when remaps(); throws
  /// InputError as apply() does.
  cv::Mat1f sourceFrame(const cv::Mat& image, ChannelOrder order = ChannelOrder::kBgr) const;
  /// The camera of sourceFrame()'s pixels (intrinsics and their size, the lens's distortion):
  /// remapping sourceFrame() from it to intrinsics() gives apply()'s working frame. Only when
  /// remaps().
  const CameraParameters& sourceCamera() const { return source_camera_; }
  static constexpr int kSourceMargin = 2;

  /// What to tell the user, one line each: how a calibration of another resolution is mapped
  /// (describeSizeMapping) and what is undistorted (describe()); empty when neither applies.
  std::vector<std::string> notes() const;
  /// One line: what is undone and the intrinsics of the result.
  std::string describe() const;

 private:
  void setUp(int working_size);
  /// The part of the frame the working frame samples, grey float, shrunk (see reduced_).
  cv::Mat1f sampledPart(const cv::Mat& image, ChannelOrder order) const;

  cv::Size image_size_;
  std::string source_;
  CameraParameters calibration_;  // as given
  CameraParameters input_;
  Intrinsics output_;
  double working_fx_ = 0.0;
  double lens_fx_ = 0.0;     // the lens's focal length at the working scale, for describe()
  double kept_width_ = 1.0;  // horizontal field of view kept, fraction of the lens's square's
  cv::Rect roi_;             // the part of the frame the working frame comes from
  cv::Size reduced_;         // roi_ shrunk to about the working scale first (empty: not shrunk)
  cv::Mat map_xy_, map_fraction_;  // fixed-point maps (cv::convertMaps) into roi_ (or reduced_)
  CameraParameters source_camera_;  // of roi_ (or reduced_) with the margin, see sourceFrame()
};

}  // namespace oefmt
