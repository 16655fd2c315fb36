// SPDX-License-Identifier: GPL-3.0-or-later
// Image streams in ROS 1 bags: reading raw sensor_msgs/Image (common encodings) or
// sensor_msgs/CompressedImage with intrinsics from a CameraInfo topic, and writing flights.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>

#include "oefmt/io/dataset.h"

namespace oefmt {

/// Thrown when a bag cannot be opened, read or written, a topic is missing, or an image cannot be
/// decoded. The message names the bag, topic or encoding.
class BagError : public std::runtime_error {
 public:
  explicit BagError(const std::string& what) : std::runtime_error(what) {}
};

/// Encodings of sensor_msgs/Image that imageFromMessage decodes.
const std::vector<std::string>& supportedImageEncodings();

/// A copy of the message's pixels: grey as mono 8/16-bit or 32/64-bit float, colour in OpenCV's
/// BGR(A) order (rgb8/rgba8/rgb16/rgba16 are reordered). Big-endian data is byte-swapped.
/// Throws BagError for an unsupported encoding or inconsistent sizes.
cv::Mat imageFromMessage(const sensor_msgs::Image& message);

/// Decodes a CompressedImage (PNG, JPEG, ... via cv::imdecode; colour in BGR order).
/// Throws BagError when it cannot be decoded.
cv::Mat imageFromMessage(const sensor_msgs::CompressedImage& message);

/// A sensor_msgs/Image holding `image` (8UC1 mono8, 16UC1 mono16, 8UC3 bgr8, 8UC4 bgra8,
/// 16UC3 bgr16, 32FC1, 64FC1). Throws BagError for another type.
sensor_msgs::Image imageMessage(const cv::Mat& image, double stamp, const std::string& frame_id);

/// CameraInfo of `camera`: plumb_bob with D = (k1, k2, p1, p2, k3) (rational_polynomial with
/// the eight coefficients when k4..k6 are not zero), K, R = I, P = [K | 0].
sensor_msgs::CameraInfo cameraInfoMessage(const CameraParameters& camera, double stamp,
                                          const std::string& frame_id);
/// Intrinsics and distortion of a CameraInfo: plumb_bob (D = k1 k2 p1 p2 [k3]) or
/// rational_polynomial (D = k1 k2 p1 p2 k3 k4 k5 k6); an empty model only without distortion.
/// Throws BagError, naming the model, for another model (e.g. equidistant), for more coefficients
/// than the model has, for a zero K and for non-finite values.
CameraParameters cameraFromInfo(const sensor_msgs::CameraInfo& info);

/// One image read from a bag.
struct BagFrame {
  cv::Mat image;         ///< see imageFromMessage
  double stamp = 0.0;    ///< header stamp [s]; the bag's record time when the header's is zero
  std::string encoding;  ///< the Image encoding, or "compressed <format>"
  std::string frame_id;
};

/// Reads the frames of one image topic of a bag in time order.
class BagImageReader {
 public:
  /// image_topic empty: the bag's only sensor_msgs/Image or CompressedImage topic.
  /// camera_info_topic empty: "<namespace of the image topic>/camera_info" if present, else the
  /// bag's only CameraInfo topic if there is one, else none. "-" disables intrinsics.
  /// Throws BagError when the bag cannot be opened or the topic is missing or ambiguous.
  explicit BagImageReader(const std::string& path, const std::string& image_topic = "",
                          const std::string& camera_info_topic = "");
  ~BagImageReader();
  BagImageReader(const BagImageReader&) = delete;
  BagImageReader& operator=(const BagImageReader&) = delete;

  const std::string& imageTopic() const;
  bool compressed() const;
  /// Number of image messages.
  std::size_t size() const;
  /// Reads the next frame; false at the end. Throws BagError for an undecodable image.
  bool next(BagFrame& frame);

  bool hasCamera() const;
  const std::string& cameraInfoTopic() const;
  /// From the first CameraInfo message (valid only when hasCamera()).
  const CameraParameters& camera() const;

 private:
  struct State;
  std::unique_ptr<State> state_;
};

struct BagWriterOptions {
  std::string image_topic = "/camera/image_raw";
  std::string camera_info_topic = "/camera/camera_info";
  std::string frame_id = "camera_optical";
  std::string compression = "none";  ///< bag chunk compression: none, lz4 or bz2
  /// Empty: raw sensor_msgs/Image. "png" or "jpg": sensor_msgs/CompressedImage in that format.
  std::string image_format;
};

/// Writes images and their CameraInfo (same stamp) to a new bag.
class BagFlightWriter {
 public:
  /// Throws BagError when the bag cannot be created or an option is invalid.
  BagFlightWriter(const std::string& path, const CameraParameters& camera, const BagWriterOptions& options);
  ~BagFlightWriter();
  BagFlightWriter(const BagFlightWriter&) = delete;
  BagFlightWriter& operator=(const BagFlightWriter&) = delete;

  /// stamp > 0 [s]. Throws BagError for an unsupported image type or a write failure.
  void write(const cv::Mat& image, double stamp);
  /// Closes the bag (also done by the destructor). Throws BagError on failure.
  void close();
  std::size_t written() const { return written_; }

 private:
  struct State;
  std::unique_ptr<State> state_;
  CameraParameters camera_;
  BagWriterOptions options_;
  std::size_t written_ = 0;
};

struct FolderToBagOptions {
  BagWriterOptions writer;
  /// Used when the dataset has no usable timestamps.txt: stamp k = start_time + k / rate.
  double rate = 5.0;
  double start_time = 1.0;
};

/// Writes every image of `dataset` with its stamp and the dataset's intrinsics (of the images as
/// stored) to a new bag; images are stored as read (8/16-bit, grey or colour). progress(k) is
/// called after frame k. Returns the number of frames. Throws BagError or DatasetError.
std::size_t convertFolderToBag(const FolderDataset& dataset, const std::string& bag_path,
                               const FolderToBagOptions& options,
                               const std::function<void(std::size_t)>& progress = {});

}  // namespace oefmt
