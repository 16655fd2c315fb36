// SPDX-License-Identifier: GPL-3.0-or-later
// Image streams in ROS 1 bags: reading raw sensor_msgs/Image or sensor_msgs/CompressedImage
// (converted by cv_bridge) with intrinsics from a CameraInfo topic, and writing flights.
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>

#include "oefmt/io/dataset.h"
#include "oefmt/io/vehicle_data.h"

namespace oefmt {

/// Thrown when a bag cannot be opened, read or written, a topic is missing, or an image cannot be
/// decoded. The message names the bag, topic or encoding.
class BagError : public std::runtime_error {
 public:
  explicit BagError(const std::string& what) : std::runtime_error(what) {}
};

/// The message's pixels as the estimator takes them, converted by cv_bridge: encodings that say
/// what their channels are (mono, colour, Bayer, yuv422) become grey as OpenCV weighs colours,
/// mono16 for 16-bit ones, mono8 otherwise; generic ones (8UC1, 16UC1, 32FC1, 64FC1; 8UC3 and
/// the like, taken as BGR(A) by the estimator) come as stored. Big-endian data is byte-swapped.
/// Throws BagError, naming the encoding, for an encoding cv_bridge does not know or cannot make
/// grey, other pixel types (signed, two channels), no pixels, or a step and data size that do
/// not fit the width, height and encoding.
cv::Mat imageFromMessage(const sensor_msgs::Image& message);

/// Decodes a CompressedImage with cv_bridge (cv::imdecode: PNG, JPEG, ...) and makes it grey at
/// its own depth (8 bits, or 16 for a 16-bit PNG). Throws BagError when it cannot be decoded.
cv::Mat imageFromMessage(const sensor_msgs::CompressedImage& message);

/// A sensor_msgs/Image holding `image` (8UC1 mono8, 16UC1 mono16, 8UC3 bgr8, 8UC4 bgra8,
/// 16UC3 bgr16, 32FC1, 64FC1). Throws BagError for another type.
sensor_msgs::Image imageMessage(const cv::Mat& image, double stamp, const std::string& frame_id);

/// CameraInfo of `camera`: plumb_bob with D = (k1, k2, p1, p2, k3) (rational_polynomial with
/// the eight coefficients when k4..k6 are not zero), K, R = I, P = [K | 0].
sensor_msgs::CameraInfo cameraInfoMessage(const CameraParameters& camera, double stamp,
                                          const std::string& frame_id);
/// Intrinsics and distortion of a CameraInfo, read by image_geometry's camera model: K and the
/// size of the images as sent (binning and a region of interest applied); plumb_bob (D = k1 k2
/// p1 p2 [k3]) or rational_polynomial (D = k1 k2 p1 p2 k3 k4 k5 k6); an empty model only without
/// distortion.
/// Throws BagError, naming the model, for another model (e.g. equidistant), for more coefficients
/// than the model has, for a zero K and for non-finite values.
CameraParameters cameraFromInfo(const sensor_msgs::CameraInfo& info);

/// One image read from a bag.
struct BagFrame {
  cv::Mat image;         ///< see imageFromMessage (grey, or as stored for generic encodings)
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
  std::string imu_topic = "/imu/data";
  std::string range_topic = "/rangefinder/range";
  /// Frames of the static transforms writeMounts() writes: the body, the IMU, the rangefinder.
  std::string base_frame = "base_link";
  std::string imu_frame = "imu_link";
  std::string range_frame = "rangefinder";
  /// The IMU frame's orientation in the body (base_frame): writeImu() gives the IMU's own
  /// orientation, angular velocity and specific force, writeMounts() this mount.
  Eigen::Quaterniond imu_mount = Eigen::Quaterniond::Identity();
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
  /// A sensor_msgs/Imu on imu_topic (frame imu_frame; `sample` is the body's) and a sensor_msgs/Range on range_topic
  /// (frame range_frame). Throws BagError for a write failure.
  void writeImu(const ImuSample& sample);
  void writeRange(const RangeSample& sample);
  /// /tf_static at `stamp`: base -> camera (frame_id; looking down the body's -z, image right on
  /// the body's x), base -> IMU (imu_mount), base -> rangefinder (its x axis down the body's -z).
  void writeMounts(double stamp);
  /// Closes the bag (also done by the destructor). Throws BagError on failure.
  void close();
  std::size_t written() const { return written_; }

 private:
  /// One message on `topic` at `stamp` (BagError when closed or on a write failure).
  template <typename Message>
  void writeMessage(const std::string& topic, double stamp, const Message& message);

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
