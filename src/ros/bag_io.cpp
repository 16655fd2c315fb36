// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/ros/bag_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>

#include <boost/make_shared.hpp>
#include <cv_bridge/cv_bridge.h>
#include <image_geometry/pinhole_camera_model.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/distortion_models.h>
#include <sensor_msgs/image_encodings.h>
#include <tf2_msgs/TFMessage.h>

#include "oefmt/error.h"
#include "oefmt/io/image_encoding.h"
#include "oefmt/ros/vehicle_messages.h"

namespace oefmt {
namespace {

namespace enc = sensor_msgs::image_encodings;

std::string sizeText(std::uint64_t width, std::uint64_t height) {
  return std::to_string(width) + "x" + std::to_string(height);
}

// Encodings that say what their channels are (grey, colour, a Bayer mosaic, YUV): cv_bridge
// turns them into grey. The generic ones (8UC1, 32FC1, ...) say only how they are stored.
bool hasColourMeaning(const std::string& encoding) {
  return enc::isMono(encoding) || enc::isColor(encoding) || enc::isBayer(encoding) || encoding == enc::YUV422;
}

std::string joined(const std::vector<std::string>& items) {
  std::string text;
  for (const std::string& item : items) text += (text.empty() ? "" : ", ") + item;
  return text.empty() ? "none" : text;
}

// "/camera/image_raw" -> "/camera"; "/camera/image_raw/compressed" -> "/camera".
std::string imageNamespace(std::string topic) {
  const std::string suffix = "/compressed";
  if (topic.size() > suffix.size() && topic.compare(topic.size() - suffix.size(), suffix.size(), suffix) == 0) {
    topic.erase(topic.size() - suffix.size());
  }
  const auto slash = topic.find_last_of('/');
  return slash == std::string::npos ? "" : topic.substr(0, slash);
}

ros::Time rosTime(double stamp) {
  if (!(stamp > 0.0) || !std::isfinite(stamp)) {
    throw BagError("bag stamps must be > 0 s (ROS time), got " + std::to_string(stamp));
  }
  return ros::Time(stamp);
}

}  // namespace

cv::Mat imageFromMessage(const sensor_msgs::Image& message) {
  const std::string& encoding = message.encoding;
  const std::string what = "'" + encoding + "' image of " + sizeText(message.width, message.height);
  int type = -1;
  try {
    type = cv_bridge::getCvType(encoding);
  } catch (const cv_bridge::Exception& e) {
    throw BagError("unsupported image encoding '" + encoding + "' (" + e.what() + ")");
  }
  // cv_bridge checks the step and size too, but in 32-bit arithmetic (which can wrap) and only
  // after it has taken the address of the first byte (of no data, too): checked here first.
  if (message.width == 0 || message.height == 0) throw BagError(what + ": no pixels");
  constexpr std::uint32_t kMaxSide = std::numeric_limits<int>::max();  // cv::Mat's
  if (message.width > kMaxSide || message.height > kMaxSide) throw BagError(what + ": too large");
  const std::uint64_t row_bytes = std::uint64_t{message.width} * CV_ELEM_SIZE(type);
  const std::uint64_t needed = std::uint64_t{message.step} * message.height;
  if (message.step < row_bytes || message.data.size() != needed) {
    throw BagError(what + " has step " + std::to_string(message.step) + " and " +
                   std::to_string(message.data.size()) + " bytes: " +
                   (message.step < row_bytes ? "a row needs " + std::to_string(row_bytes)
                                             : std::string(message.data.size() < needed ? "too few" : "too many") +
                                                   " (height x step = " + std::to_string(needed) + ")"));
  }
  if (message.step % CV_ELEM_SIZE1(type) != 0) {  // OpenCV's rows start on a whole channel value
    throw BagError(what + " has step " + std::to_string(message.step) + ": not a multiple of its " +
                   std::to_string(CV_ELEM_SIZE1(type)) + "-byte channel values");
  }
  try {
    // The pixels as stored: shared with the message, or a copy when they had to be byte-swapped.
    const cv_bridge::CvImageConstPtr stored = cv_bridge::toCvShare(message, nullptr);
    cv_bridge::CvImageConstPtr pixels = stored;
    if (stored->image.type() != type) {
      // cv_bridge byte-swaps big-endian pixels but hands them back as 8-bit channels: the bytes
      // are right, their type is the encoding's (a view of `stored`, alive until the copy below).
      const cv::Mat& swapped = stored->image;
      pixels = boost::make_shared<cv_bridge::CvImage>(
          stored->header, encoding, cv::Mat(swapped.rows, swapped.cols, type, swapped.data, swapped.step));
    }
    if (hasColourMeaning(encoding)) {
      // Grey as OpenCV's cvtColor weighs the channels (demosaiced for Bayer), at 8 or 16 bits.
      return cv_bridge::cvtColor(pixels, enc::bitDepth(encoding) == 16 ? enc::MONO16 : enc::MONO8)->image;
    }
    const int depth = CV_MAT_DEPTH(type), channels = CV_MAT_CN(type);
    if ((depth != CV_8U && depth != CV_16U && depth != CV_32F && depth != CV_64F) ||
        (channels != 1 && channels != 3 && channels != 4)) {
      throw BagError("unsupported image encoding '" + encoding +
                     "': the estimator takes grey or colour encodings, or 1, 3 or 4 channels (three "
                     "or four as BGR(A)) of 8/16-bit unsigned or float pixels");
    }
    return pixels->image.clone();
  } catch (const cv_bridge::Exception& e) {
    throw BagError(what + ": " + e.what());
  } catch (const cv::Exception& e) {  // from OpenCV's conversion (e.err: without file and line)
    throw BagError(what + ": " + e.err);
  }
}

cv::Mat imageFromMessage(const sensor_msgs::CompressedImage& message) {
  const std::string what = "compressed image (format '" + message.format + "', " +
                           std::to_string(message.data.size()) + " bytes)";
  if (message.data.empty()) throw BagError("cannot decode " + what + ": no data");
  cv::Mat image;
  try {
    // Decoded as stored (cv::imdecode, IMREAD_UNCHANGED) and made grey at its own depth:
    // cv_bridge names every one-channel result mono8, but a 16-bit PNG keeps its 16 bits.
    const cv_bridge::CvImagePtr decoded = cv_bridge::toCvCopy(message, enc::MONO8);
    if (decoded) image = decoded->image;
  } catch (const cv_bridge::Exception& e) {
    throw BagError("cannot decode " + what + ": " + e.what());
  } catch (const cv::Exception& e) {  // from cv::imdecode
    throw BagError("cannot decode " + what + ": " + e.err);
  }
  if (image.empty()) throw BagError("cannot decode " + what);
  return image;
}

sensor_msgs::Image imageMessage(const cv::Mat& image, double stamp, const std::string& frame_id) {
  std::string encoding;
  switch (image.type()) {
    case CV_8UC1: encoding = enc::MONO8; break;
    case CV_16UC1: encoding = enc::MONO16; break;
    case CV_8UC3: encoding = enc::BGR8; break;
    case CV_8UC4: encoding = enc::BGRA8; break;
    case CV_16UC3: encoding = enc::BGR16; break;
    case CV_32FC1: encoding = enc::TYPE_32FC1; break;
    case CV_64FC1: encoding = enc::TYPE_64FC1; break;
    default: throw BagError("cannot store an image of type " + cv::typeToString(image.type()) + " in a bag");
  }
  std_msgs::Header header;
  header.stamp = rosTime(stamp);
  header.frame_id = frame_id;
  sensor_msgs::Image message;
  cv_bridge::CvImage(header, encoding, image).toImageMsg(message);
  return message;
}

sensor_msgs::CameraInfo cameraInfoMessage(const CameraParameters& camera, double stamp,
                                          const std::string& frame_id) {
  const Intrinsics& k = camera.intrinsics;
  const Distortion& d = camera.distortion;
  sensor_msgs::CameraInfo info;
  info.header.stamp = rosTime(stamp);
  info.header.frame_id = frame_id;
  info.width = static_cast<std::uint32_t>(k.width);
  info.height = static_cast<std::uint32_t>(k.height);
  if (d.rational()) {
    info.distortion_model = sensor_msgs::distortion_models::RATIONAL_POLYNOMIAL;
    info.D = {d.k1, d.k2, d.p1, d.p2, d.k3, d.k4, d.k5, d.k6};
  } else {
    info.distortion_model = sensor_msgs::distortion_models::PLUMB_BOB;
    info.D = {d.k1, d.k2, d.p1, d.p2, d.k3};
  }
  info.K = {k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0};
  info.R = {1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0};
  info.P = {k.fx, 0.0, k.cx, 0.0, 0.0, k.fy, k.cy, 0.0, 0.0, 0.0, 1.0, 0.0};
  return info;
}

CameraParameters cameraFromInfo(const sensor_msgs::CameraInfo& info) {
  for (double value : info.K) {
    if (!std::isfinite(value)) throw BagError("CameraInfo K is not finite");
  }
  for (double d : info.D) {
    if (!std::isfinite(d)) throw BagError("CameraInfo distortion coefficients (D) are not finite");
  }
  const bool any = std::any_of(info.D.begin(), info.D.end(), [](double d) { return d != 0.0; });
  // OpenCV's coefficient order: k1 k2 p1 p2 k3 (plumb_bob), then k4 k5 k6 (rational_polynomial).
  std::size_t count = 0;
  if (info.distortion_model == sensor_msgs::distortion_models::PLUMB_BOB) {
    count = 5;
  } else if (info.distortion_model == sensor_msgs::distortion_models::RATIONAL_POLYNOMIAL) {
    count = 8;
  } else if (!info.distortion_model.empty() || any) {
    // A fisheye ("equidistant") or other model is not a pinhole: refused rather than misread.
    // An empty model is fine without coefficients (uncalibrated drivers publish that).
    throw BagError("CameraInfo distortion model '" + info.distortion_model +
                   "' is not supported (plumb_bob, rational_polynomial)");
  }
  for (std::size_t i = count; i < info.D.size(); ++i) {
    if (info.D[i] != 0.0) {
      throw BagError("CameraInfo has " + std::to_string(info.D.size()) + " distortion coefficients; " +
                     info.distortion_model + " has " + std::to_string(count));
    }
  }
  // image_geometry's camera model gives K for the images as sent: binned, and shifted to a
  // region of interest, as the CameraInfo says.
  image_geometry::PinholeCameraModel model;
  model.fromCameraInfo(info);
  const cv::Matx33d& matrix = model.intrinsicMatrix();
  CameraParameters camera;
  Intrinsics& k = camera.intrinsics;
  k.fx = matrix(0, 0);
  k.fy = matrix(1, 1);
  k.cx = matrix(0, 2);
  k.cy = matrix(1, 2);
  const cv::Rect roi = model.rawRoi();
  k.width = roi.width / static_cast<int>(model.binningX());
  k.height = roi.height / static_cast<int>(model.binningY());
  if (!(k.fx > 0.0 && k.fy > 0.0)) throw BagError("CameraInfo has no calibration (K is zero)");
  const cv::Mat_<double>& coefficients = model.distortionCoeffs();
  const auto coefficient = [&coefficients](int i) { return i < static_cast<int>(coefficients.total()) ? coefficients(i) : 0.0; };
  Distortion& d = camera.distortion;
  d.k1 = coefficient(0);
  d.k2 = coefficient(1);
  d.p1 = coefficient(2);
  d.p2 = coefficient(3);
  d.k3 = coefficient(4);
  d.k4 = coefficient(5);
  d.k5 = coefficient(6);
  d.k6 = coefficient(7);
  return camera;
}

// ------------------------------------------------------------------------------------------------

struct BagImageReader::State {
  std::string path;
  rosbag::Bag bag;
  std::string image_topic;
  std::string info_topic;
  bool compressed = false;
  bool has_camera = false;
  CameraParameters camera;
  std::unique_ptr<rosbag::View> view;
  rosbag::View::iterator position;
};

BagImageReader::BagImageReader(const std::string& path, const std::string& image_topic,
                               const std::string& camera_info_topic)
    : state_(std::make_unique<State>()) {
  State& s = *state_;
  s.path = path;
  try {
    s.bag.open(path, rosbag::bagmode::Read);
  } catch (const rosbag::BagException& e) {
    throw BagError("cannot open bag '" + path + "': " + e.what());
  }
  std::map<std::string, std::string> types;  // topic -> datatype
  {
    rosbag::View all(s.bag);
    for (const rosbag::ConnectionInfo* connection : all.getConnections()) {
      types[connection->topic] = connection->datatype;
    }
  }
  std::vector<std::string> image_topics, info_topics;
  for (const auto& [topic, type] : types) {
    if (type == "sensor_msgs/Image" || type == "sensor_msgs/CompressedImage") image_topics.push_back(topic);
    if (type == "sensor_msgs/CameraInfo") info_topics.push_back(topic);
  }
  if (image_topic.empty()) {
    if (image_topics.size() != 1) {
      throw BagError("bag '" + path + "' has " + std::to_string(image_topics.size()) +
                     " image topics (" + joined(image_topics) + "): choose one");
    }
    s.image_topic = image_topics.front();
  } else {
    s.image_topic = image_topic;
    const auto found = types.find(image_topic);
    if (found == types.end()) {
      throw BagError("bag '" + path + "' has no topic '" + image_topic + "' (image topics: " + joined(image_topics) + ")");
    }
    if (std::find(image_topics.begin(), image_topics.end(), image_topic) == image_topics.end()) {
      throw BagError("topic '" + image_topic + "' of bag '" + path + "' carries " + found->second +
                     ", not sensor_msgs/Image or CompressedImage");
    }
  }
  s.compressed = types[s.image_topic] == "sensor_msgs/CompressedImage";

  if (camera_info_topic != "-") {
    if (!camera_info_topic.empty()) {
      if (types.count(camera_info_topic) == 0 || types[camera_info_topic] != "sensor_msgs/CameraInfo") {
        throw BagError("bag '" + path + "' has no CameraInfo topic '" + camera_info_topic +
                       "' (CameraInfo topics: " + joined(info_topics) + ")");
      }
      s.info_topic = camera_info_topic;
    } else {
      const std::string sibling = imageNamespace(s.image_topic) + "/camera_info";
      if (types.count(sibling) && types[sibling] == "sensor_msgs/CameraInfo") {
        s.info_topic = sibling;
      } else if (info_topics.size() == 1) {
        s.info_topic = info_topics.front();
      }
    }
  }
  if (!s.info_topic.empty()) {
    rosbag::View infos(s.bag, rosbag::TopicQuery(s.info_topic));
    for (const rosbag::MessageInstance& message : infos) {
      const auto info = message.instantiate<sensor_msgs::CameraInfo>();
      if (!info) continue;
      try {
        s.camera = cameraFromInfo(*info);
      } catch (const BagError& e) {
        throw BagError("bag '" + path + "', " + s.info_topic + ": " + e.what());
      }
      s.has_camera = true;
      break;
    }
  }
  s.view = std::make_unique<rosbag::View>(s.bag, rosbag::TopicQuery(s.image_topic));
  s.position = s.view->begin();
}

BagImageReader::~BagImageReader() = default;

const std::string& BagImageReader::imageTopic() const { return state_->image_topic; }
bool BagImageReader::compressed() const { return state_->compressed; }
std::size_t BagImageReader::size() const { return state_->view->size(); }
bool BagImageReader::hasCamera() const { return state_->has_camera; }
const std::string& BagImageReader::cameraInfoTopic() const { return state_->info_topic; }
const CameraParameters& BagImageReader::camera() const { return state_->camera; }

bool BagImageReader::next(BagFrame& frame) {
  State& s = *state_;
  if (s.position == s.view->end()) return false;
  const rosbag::MessageInstance& message = *s.position;
  const std::string where = " (topic '" + s.image_topic + "' of bag '" + s.path + "')";
  std_msgs::Header header;
  try {
    if (s.compressed) {
      const auto compressed = message.instantiate<sensor_msgs::CompressedImage>();
      if (!compressed) throw BagError("unreadable CompressedImage message");
      frame.image = imageFromMessage(*compressed);
      frame.encoding = "compressed " + compressed->format;
      header = compressed->header;
    } else {
      const auto image = message.instantiate<sensor_msgs::Image>();
      if (!image) throw BagError("unreadable Image message");
      frame.image = imageFromMessage(*image);
      frame.encoding = image->encoding;
      header = image->header;
    }
  } catch (const BagError& e) {
    throw BagError(e.what() + where);
  } catch (const rosbag::BagException& e) {
    throw BagError(std::string("cannot read message: ") + e.what() + where);
  }
  frame.stamp = header.stamp.isZero() ? message.getTime().toSec() : header.stamp.toSec();
  frame.frame_id = header.frame_id;
  ++s.position;
  return true;
}

// ------------------------------------------------------------------------------------------------

struct BagFlightWriter::State {
  rosbag::Bag bag;
  std::string path;
  bool open = false;
};

BagFlightWriter::BagFlightWriter(const std::string& path, const CameraParameters& camera,
                                 const BagWriterOptions& options)
    : state_(std::make_unique<State>()), camera_(camera), options_(options) {
  if (options_.image_format != "" && options_.image_format != "png" && options_.image_format != "jpg") {
    throw BagError("image format must be raw (empty), png or jpg, got '" + options_.image_format + "'");
  }
  rosbag::compression::CompressionType compression = rosbag::compression::Uncompressed;
  if (options_.compression == "lz4") {
    compression = rosbag::compression::LZ4;
  } else if (options_.compression == "bz2") {
    compression = rosbag::compression::BZ2;
  } else if (options_.compression != "none") {
    throw BagError("bag compression must be none, lz4 or bz2, got '" + options_.compression + "'");
  }
  if (options_.image_topic.empty() || options_.camera_info_topic.empty()) throw BagError("empty topic name");
  state_->path = path;
  try {
    state_->bag.open(path, rosbag::bagmode::Write);
    state_->bag.setCompression(compression);
  } catch (const rosbag::BagException& e) {
    throw BagError("cannot create bag '" + path + "': " + e.what());
  }
  state_->open = true;
}

BagFlightWriter::~BagFlightWriter() {
  try {
    close();
  } catch (const BagError&) {
    // A destructor must not throw; call close() to see the error.
  }
}

void BagFlightWriter::write(const cv::Mat& image, double stamp) {
  if (!state_->open) throw BagError("bag '" + state_->path + "' is closed");
  const ros::Time time = rosTime(stamp);
  try {
    if (options_.image_format.empty()) {
      state_->bag.write(options_.image_topic, time, imageMessage(image, stamp, options_.frame_id));
    } else {
      sensor_msgs::CompressedImage message;
      message.header.stamp = time;
      message.header.frame_id = options_.frame_id;
      message.format = options_.image_format;
      message.data = encodeImage(options_.image_format, image);
      state_->bag.write(options_.image_topic, time, message);
    }
    state_->bag.write(options_.camera_info_topic, time, cameraInfoMessage(camera_, stamp, options_.frame_id));
  } catch (const rosbag::BagException& e) {
    throw BagError("cannot write to bag '" + state_->path + "': " + e.what());
  } catch (const std::exception& e) {
    throw BagError("cannot encode image for bag '" + state_->path + "': " + e.what());
  }
  ++written_;
}

void BagFlightWriter::writeImu(const ImuSample& sample) {
  // The IMU's own frame: world <- imu = (world <- body)(body <- imu); vectors turned into it.
  ImuSample own = sample;
  const Eigen::Quaterniond& mount = options_.imu_mount;
  own.orientation = (sample.orientation * mount).normalized();
  own.angular_velocity = mount.conjugate() * sample.angular_velocity;
  own.linear_acceleration = mount.conjugate() * sample.linear_acceleration;
  writeMessage(options_.imu_topic, sample.stamp, imuMessage(own, options_.imu_frame));
}

void BagFlightWriter::writeRange(const RangeSample& sample) {
  writeMessage(options_.range_topic, sample.stamp, rangeMessage(sample, options_.range_frame));
}

void BagFlightWriter::writeMounts(double stamp) {
  tf2_msgs::TFMessage mounts;
  const double half = std::sqrt(0.5);
  mounts.transforms.push_back(staticTransform(options_.base_frame, options_.frame_id, stamp, 1.0, 0.0, 0.0, 0.0));
  const Eigen::Quaterniond imu = options_.imu_mount.normalized();
  mounts.transforms.push_back(staticTransform(options_.base_frame, options_.imu_frame, stamp, imu.x(), imu.y(), imu.z(), imu.w()));
  // +90 degrees about y: the rangefinder's x (its beam) along the body's -z.
  mounts.transforms.push_back(staticTransform(options_.base_frame, options_.range_frame, stamp, 0.0, half, 0.0, half));
  writeMessage("/tf_static", stamp, mounts);
}

template <typename Message>
void BagFlightWriter::writeMessage(const std::string& topic, double stamp, const Message& message) {
  if (!state_->open) throw BagError("bag '" + state_->path + "' is closed");
  try {
    state_->bag.write(topic, rosTime(stamp), message);
  } catch (const rosbag::BagException& e) {
    throw BagError("cannot write to bag '" + state_->path + "': " + e.what());
  }
}

void BagFlightWriter::close() {
  if (!state_->open) return;
  state_->open = false;
  try {
    state_->bag.close();
  } catch (const rosbag::BagException& e) {
    throw BagError("cannot close bag '" + state_->path + "': " + e.what());
  }
}

std::size_t convertFolderToBag(const FolderDataset& dataset, const std::string& bag_path,
                               const FolderToBagOptions& options,
                               const std::function<void(std::size_t)>& progress) {
  if (!dataset.hasTimestamps() && !(options.rate > 0.0 && options.start_time > 0.0)) {
    throw BagError("rate and start time must be > 0");
  }
  BagFlightWriter writer(bag_path, dataset.camera(), options.writer);
  for (std::size_t k = 0; k < dataset.size(); ++k) {
    const double stamp = dataset.hasTimestamps() ? dataset.timestamp(k)
                                                 : options.start_time + static_cast<double>(k) / options.rate;
    writer.write(dataset.loadImage(k), stamp);
    if (progress) progress(k);
  }
  writer.close();
  return writer.written();
}

}  // namespace oefmt
