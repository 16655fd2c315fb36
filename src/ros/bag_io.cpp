// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/ros/bag_io.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <map>

#include <opencv2/imgproc.hpp>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/distortion_models.h>

#include "oefmt/error.h"
#include "oefmt/io/image_decoding.h"
#include "oefmt/io/image_encoding.h"

namespace oefmt {
namespace {

struct EncodingInfo {
  int type;
  bool swap_red_blue;
  int demosaic = -1;  ///< cv::COLOR_Bayer*2BGR code for Bayer patterns
};

const std::map<std::string, EncodingInfo>& encodingTable() {
  static const std::map<std::string, EncodingInfo> table = {
      {"mono8", {CV_8UC1, false}},   {"8UC1", {CV_8UC1, false}},    {"mono16", {CV_16UC1, false}},
      {"16UC1", {CV_16UC1, false}},  {"bgr8", {CV_8UC3, false}},    {"rgb8", {CV_8UC3, true}},
      {"8UC3", {CV_8UC3, false}},    {"bgra8", {CV_8UC4, false}},   {"rgba8", {CV_8UC4, true}},
      {"8UC4", {CV_8UC4, false}},    {"bgr16", {CV_16UC3, false}},  {"rgb16", {CV_16UC3, true}},
      {"16UC3", {CV_16UC3, false}},  {"bgra16", {CV_16UC4, false}}, {"rgba16", {CV_16UC4, true}},
      {"16UC4", {CV_16UC4, false}},  {"32FC1", {CV_32FC1, false}},  {"64FC1", {CV_64FC1, false}},
      // Raw Bayer mosaics, demosaiced to BGR. OpenCV names a pattern by its second row's
      // start, as cv_bridge maps them: rggb -> BayerBG, bggr -> BayerRG, gbrg -> BayerGR, grbg -> BayerGB.
      {"bayer_rggb8", {CV_8UC1, false, cv::COLOR_BayerBG2BGR}},
      {"bayer_bggr8", {CV_8UC1, false, cv::COLOR_BayerRG2BGR}},
      {"bayer_gbrg8", {CV_8UC1, false, cv::COLOR_BayerGR2BGR}},
      {"bayer_grbg8", {CV_8UC1, false, cv::COLOR_BayerGB2BGR}},
      {"bayer_rggb16", {CV_16UC1, false, cv::COLOR_BayerBG2BGR}},
      {"bayer_bggr16", {CV_16UC1, false, cv::COLOR_BayerRG2BGR}},
      {"bayer_gbrg16", {CV_16UC1, false, cv::COLOR_BayerGR2BGR}},
      {"bayer_grbg16", {CV_16UC1, false, cv::COLOR_BayerGB2BGR}},
  };
  return table;
}

bool hostIsBigEndian() {
  const std::uint16_t probe = 1;
  unsigned char first = 0;
  std::memcpy(&first, &probe, 1);
  return first == 0;
}

void swapBytes(cv::Mat& image) {
  const std::size_t size = image.elemSize1();
  if (size == 1) return;
  for (int r = 0; r < image.rows; ++r) {
    unsigned char* p = image.ptr<unsigned char>(r);
    const std::size_t count = static_cast<std::size_t>(image.cols) * image.channels();
    for (std::size_t i = 0; i < count; ++i, p += size) std::reverse(p, p + size);
  }
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

const std::vector<std::string>& supportedImageEncodings() {
  static const std::vector<std::string> names = [] {
    std::vector<std::string> out;
    for (const auto& entry : encodingTable()) out.push_back(entry.first);
    return out;
  }();
  return names;
}

cv::Mat imageFromMessage(const sensor_msgs::Image& message) {
  const auto found = encodingTable().find(message.encoding);
  if (found == encodingTable().end()) {
    throw BagError("unsupported image encoding '" + message.encoding + "' (supported: " +
                   joined(supportedImageEncodings()) + ")");
  }
  const EncodingInfo info = found->second;
  const int rows = static_cast<int>(message.height), cols = static_cast<int>(message.width);
  if (rows <= 0 || cols <= 0) throw BagError("image message of size " + std::to_string(cols) + "x" + std::to_string(rows));
  const std::size_t row_bytes = static_cast<std::size_t>(cols) * CV_ELEM_SIZE(info.type);
  if (message.step < row_bytes || message.data.size() < static_cast<std::size_t>(message.step) * (rows - 1) + row_bytes) {
    throw BagError("image message '" + message.encoding + "' " + std::to_string(cols) + "x" + std::to_string(rows) +
                   " has step " + std::to_string(message.step) + " and " + std::to_string(message.data.size()) +
                   " bytes: too few");
  }
  cv::Mat image(rows, cols, info.type);
  for (int r = 0; r < rows; ++r) {
    std::memcpy(image.ptr(r), message.data.data() + static_cast<std::size_t>(r) * message.step, row_bytes);
  }
  if ((message.is_bigendian != 0) != hostIsBigEndian()) swapBytes(image);
  if (info.swap_red_blue) {
    cv::cvtColor(image, image, image.channels() == 3 ? cv::COLOR_RGB2BGR : cv::COLOR_RGBA2BGRA);
  }
  if (info.demosaic >= 0) {
    if (rows < 2 || cols < 2) throw BagError("Bayer image smaller than 2x2");
    cv::cvtColor(image, image, info.demosaic);
  }
  return image;
}

cv::Mat imageFromMessage(const sensor_msgs::CompressedImage& message) {
  cv::Mat image;
  if (!message.data.empty()) {
    try {
      image = decodeImage(message.data.data(), message.data.size());
    } catch (const std::exception& e) {  // an image over the size limit, no imgcodecs plugin
      throw BagError(std::string("compressed image: ") + e.what());
    }
  }
  if (image.empty()) {
    throw BagError("cannot decode compressed image (format '" + message.format + "', " +
                   std::to_string(message.data.size()) + " bytes)");
  }
  return image;
}

sensor_msgs::Image imageMessage(const cv::Mat& image, double stamp, const std::string& frame_id) {
  std::string encoding;
  switch (image.type()) {
    case CV_8UC1: encoding = "mono8"; break;
    case CV_16UC1: encoding = "mono16"; break;
    case CV_8UC3: encoding = "bgr8"; break;
    case CV_8UC4: encoding = "bgra8"; break;
    case CV_16UC3: encoding = "bgr16"; break;
    case CV_32FC1: encoding = "32FC1"; break;
    case CV_64FC1: encoding = "64FC1"; break;
    default: throw BagError("cannot store an image of type " + cv::typeToString(image.type()) + " in a bag");
  }
  sensor_msgs::Image message;
  message.header.stamp = rosTime(stamp);
  message.header.frame_id = frame_id;
  message.height = static_cast<std::uint32_t>(image.rows);
  message.width = static_cast<std::uint32_t>(image.cols);
  message.encoding = encoding;
  message.is_bigendian = hostIsBigEndian() ? 1 : 0;
  const std::size_t row_bytes = static_cast<std::size_t>(image.cols) * image.elemSize();
  message.step = static_cast<std::uint32_t>(row_bytes);
  message.data.resize(row_bytes * image.rows);
  for (int r = 0; r < image.rows; ++r) std::memcpy(&message.data[r * row_bytes], image.ptr(r), row_bytes);
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
  CameraParameters camera;
  Intrinsics& k = camera.intrinsics;
  k.fx = info.K[0];
  k.fy = info.K[4];
  k.cx = info.K[2];
  k.cy = info.K[5];
  k.width = static_cast<int>(info.width);
  k.height = static_cast<int>(info.height);
  if (!(k.fx > 0.0 && k.fy > 0.0)) throw BagError("CameraInfo has no calibration (K is zero)");
  if (!(std::isfinite(k.fx) && std::isfinite(k.fy) && std::isfinite(k.cx) && std::isfinite(k.cy))) {
    throw BagError("CameraInfo K is not finite");
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
  Distortion& d = camera.distortion;
  const auto coefficient = [&info](std::size_t i) { return i < info.D.size() ? info.D[i] : 0.0; };
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
