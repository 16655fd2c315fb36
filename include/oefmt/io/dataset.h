// SPDX-License-Identifier: GPL-3.0-or-later
// The o-eFMT authors' dataset folder layout: Images/0001.png..., imageList.txt, timestamps.txt,
// cam_param.yaml. Read exactly as their users have it; written by the flight simulator.
#pragma once

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/registration/image_prep.h"

namespace oefmt {

/// Thrown when a dataset (folder, file, image) cannot be read. The message names the path.
class DatasetError : public std::runtime_error {
 public:
  explicit DatasetError(const std::string& what) : std::runtime_error(what) {}
};

/// Radial-tangential distortion of normalised image coordinates in OpenCV's model: ROS
/// "plumb_bob" (k1, k2, p1, p2, k3) and, with k4..k6, "rational_polynomial" (radial factor
/// (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6)).
struct Distortion {
  double k1 = 0.0;
  double k2 = 0.0;
  double p1 = 0.0;
  double p2 = 0.0;
  double k3 = 0.0;
  double k4 = 0.0;
  double k5 = 0.0;
  double k6 = 0.0;
  bool any() const {
    return k1 != 0.0 || k2 != 0.0 || p1 != 0.0 || p2 != 0.0 || k3 != 0.0 || rational();
  }
  /// True when the rational model's denominator is used (k4, k5 or k6 non-zero).
  bool rational() const { return k4 != 0.0 || k5 != 0.0 || k6 != 0.0; }
  /// OpenCV's coefficient vector: (k1, k2, p1, p2, k3), plus (k4, k5, k6) when rational().
  std::vector<double> coefficients() const;
  /// "k1 -0.2 k2 0.05" (the non-zero coefficients; "none" when there are none).
  std::string text() const;
};

/// Pinhole intrinsics plus distortion, in pixels of the image of intrinsics.width x height.
struct CameraParameters {
  Intrinsics intrinsics;
  Distortion distortion;
};

/// Reads the authors' cam_param.yaml (yaml-cpp; "%YAML:1.0" header optional) with Camera.fx, fy,
/// cx, cy (required) and Camera.k1, k2, p1, p2, k3, k4, k5, k6, width, height (optional; missing
/// distortion is 0, missing size is 0). Camera.type, when given, must be "PinHole" (the model
/// above; ORB-SLAM's "KannalaBrandt8" fisheye is refused). Other keys are ignored. Throws
/// DatasetError naming the file, the line and the key for a missing or invalid key, a key given
/// twice and a file that is not one YAML map.
CameraParameters readCameraParameters(const std::string& path);

/// Writes `camera` in the same layout (the ten Camera.* keys of the authors' file, plus k3..k6 when
/// they are not zero). Throws DatasetError on failure.
void writeCameraParameters(const std::string& path, const CameraParameters& camera);

/// Intrinsics of an image of image_size made from a camera of camera.width x height by a centred
/// crop to the image's aspect ratio followed by a resize (a plain resize when the aspects agree;
/// the authors' 4056x3040 camera and 512x512 images: a centred 3040x3040 crop scaled by 512/3040).
/// Pixel centres sit at integer coordinates. Throws InputError for invalid intrinsics or size.
Intrinsics intrinsicsForImageSize(const Intrinsics& camera, cv::Size image_size);
/// That crop: the largest centred region of the camera image with the images' aspect ratio
/// [camera px]. Expects valid intrinsics and a positive size (see intrinsicsForImageSize).
cv::Size2d centredCropForImageSize(const Intrinsics& camera, cv::Size image_size);

/// Parses one line of timestamps.txt to seconds: a decimal number of seconds, or the authors'
/// 14-digit calendar stamp YYYYMMDDhhmmss (UTC). Returns false for anything else.
bool parseTimestamp(const std::string& text, double& seconds);

/// A dataset folder in the authors' layout.
///  - imageList.txt: one image name per line (relative to Images/, or to the folder); blank lines
///    and '#' comments are skipped; CR/LF and a missing final newline are tolerated. Without the
///    list, every .png/.jpg/.jpeg/.tif/.tiff/.bmp in Images/ is taken in name order.
///  - timestamps.txt (optional): one stamp per image (see parseTimestamp). When it is missing, has
///    another number of lines than there are images, or is not increasing, it is ignored with a
///    warning and frame k gets timestamp k (the index; the authors' ground truth uses it too).
///  - cam_param.yaml: intrinsics of the original camera; scaled to the images' size (see
///    intrinsicsForImageSize). Without Camera.width/height the images are taken to be the original.
/// The first image is read once to learn the image size.
class FolderDataset {
 public:
  /// Throws DatasetError when the folder, cam_param.yaml or the first image cannot be read, or
  /// when there is no image.
  explicit FolderDataset(const std::string& directory);

  std::size_t size() const { return names_.size(); }
  const std::string& directory() const { return directory_; }
  /// Name as listed in imageList.txt (e.g. "0001.png").
  const std::string& imageName(std::size_t index) const;
  /// Full path of the image file.
  const std::string& imagePath(std::size_t index) const;
  /// True when timestamps.txt was used; otherwise timestamp(k) == k.
  bool hasTimestamps() const { return has_timestamps_; }
  /// Seconds.
  double timestamp(std::size_t index) const;
  /// The image as stored (cv::IMREAD_UNCHANGED: 8/16-bit, grey/BGR/BGRA). Throws DatasetError
  /// naming the path when it is missing, unreadable, or not of the first image's size.
  cv::Mat loadImage(std::size_t index) const;
  /// Tells the operating system that image `index` will be read soon, so that it reads the file
  /// in the background (POSIX_FADV_WILLNEED). Only advice: nothing happens past the last image or
  /// where the file cannot be opened (loadImage says so when it is read).
  void adviseReading(std::size_t index) const;
  /// Size of the images (of the first one).
  cv::Size imageSize() const { return image_size_; }
  /// Intrinsics of the images as stored (already scaled from cam_param.yaml's camera).
  const Intrinsics& intrinsics() const { return camera_.intrinsics; }
  /// Distortion coefficients from cam_param.yaml (scale-free, so unchanged by the scaling).
  const Distortion& distortion() const { return camera_.distortion; }
  const CameraParameters& camera() const { return camera_; }
  /// Intrinsics as cam_param.yaml gives them (the original camera).
  const Intrinsics& fileIntrinsics() const { return file_intrinsics_; }
  /// Things that were tolerated (ignored timestamps, assumed size), for the user to see.
  const std::vector<std::string>& warnings() const { return warnings_; }

 private:
  void readImageList();
  void readTimestamps();
  void checkIndex(std::size_t index) const;

  std::string directory_;
  std::vector<std::string> names_;
  std::vector<std::string> paths_;
  std::vector<double> timestamps_;
  bool has_timestamps_ = false;
  cv::Size image_size_;
  CameraParameters camera_;
  Intrinsics file_intrinsics_;
  std::vector<std::string> warnings_;
};

}  // namespace oefmt
