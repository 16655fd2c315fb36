// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/ros/vehicle_messages.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <tf2/buffer_core.h>
#include <tf2/exceptions.h>
#include <tf2_msgs/TFMessage.h>

#include "oefmt/ros/bag_io.h"

namespace oefmt {
namespace {

ros::Time rosStamp(double stamp) {
  ros::Time time;
  time.fromSec(stamp);
  return time;
}

void diagonal(boost::array<double, 9>& covariance, double sigma) {
  covariance.fill(0.0);
  covariance[0] = covariance[4] = covariance[8] = sigma * sigma;
}

template <typename Message, typename Sample, typename Convert>
std::vector<Sample> readTopic(const std::string& bag_path, const std::string& topic, Convert convert) {
  std::vector<Sample> samples;
  if (topic.empty()) return samples;
  try {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
    rosbag::View view(bag, rosbag::TopicQuery(topic));
    if (view.size() == 0) throw BagError("bag '" + bag_path + "' has no messages on " + topic);
    for (const rosbag::MessageInstance& instance : view) {
      const auto message = instance.instantiate<Message>();
      if (!message) {
        throw BagError("bag '" + bag_path + "': " + topic + " holds " + instance.getDataType() + ", not " +
                       ros::message_traits::DataType<Message>::value());
      }
      samples.push_back(convert(*message));
    }
  } catch (const rosbag::BagException& e) {
    throw BagError("cannot read bag '" + bag_path + "': " + e.what());
  }
  std::stable_sort(samples.begin(), samples.end(), [](const Sample& a, const Sample& b) { return a.stamp < b.stamp; });
  return samples;
}

}  // namespace

sensor_msgs::Imu imuMessage(const ImuSample& s, const std::string& frame_id, const ImuNoise& noise) {
  sensor_msgs::Imu message;
  message.header.stamp = rosStamp(s.stamp);
  message.header.frame_id = frame_id;
  message.orientation.x = s.orientation.x();
  message.orientation.y = s.orientation.y();
  message.orientation.z = s.orientation.z();
  message.orientation.w = s.orientation.w();
  message.angular_velocity.x = s.angular_velocity.x();
  message.angular_velocity.y = s.angular_velocity.y();
  message.angular_velocity.z = s.angular_velocity.z();
  message.linear_acceleration.x = s.linear_acceleration.x();
  message.linear_acceleration.y = s.linear_acceleration.y();
  message.linear_acceleration.z = s.linear_acceleration.z();
  diagonal(message.orientation_covariance, noise.orientation);
  diagonal(message.angular_velocity_covariance, noise.angular_velocity);
  diagonal(message.linear_acceleration_covariance, noise.linear_acceleration);
  return message;
}

bool hasOrientation(const sensor_msgs::Imu& message) {
  const auto& q = message.orientation;
  return message.orientation_covariance[0] != -1.0 && std::isfinite(q.x) && std::isfinite(q.y) &&
         std::isfinite(q.z) && std::isfinite(q.w) && (q.x * q.x + q.y * q.y + q.z * q.z + q.w * q.w) > 1e-6;
}

ImuSample imuSample(const sensor_msgs::Imu& message) {
  ImuSample s;
  s.stamp = message.header.stamp.toSec();
  if (hasOrientation(message)) {
    s.orientation = Eigen::Quaterniond(message.orientation.w, message.orientation.x, message.orientation.y,
                                       message.orientation.z)
                        .normalized();
  }
  // A covariance of -1 says the rates were not measured (sensor_msgs/Imu): NaN, which the gyro's
  // user (TurnHistory) takes as no reading, not as a vehicle that does not turn.
  s.angular_velocity = message.angular_velocity_covariance[0] == -1.0
                           ? Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN())
                           : Eigen::Vector3d(message.angular_velocity.x, message.angular_velocity.y,
                                             message.angular_velocity.z);
  s.linear_acceleration = {message.linear_acceleration.x, message.linear_acceleration.y,
                           message.linear_acceleration.z};
  return s;
}

sensor_msgs::Range rangeMessage(const RangeSample& s, const std::string& frame_id, double max_range) {
  sensor_msgs::Range message;
  message.header.stamp = rosStamp(s.stamp);
  message.header.frame_id = frame_id;
  message.radiation_type = sensor_msgs::Range::INFRARED;
  message.field_of_view = 0.05f;  // a narrow beam (lidar rangefinders: about 2-3 degrees)
  message.min_range = 0.1f;
  message.max_range = static_cast<float>(max_range);
  message.range = static_cast<float>(s.range);
  return message;
}

RangeSample rangeSample(const sensor_msgs::Range& message) {
  RangeSample s;
  s.stamp = message.header.stamp.toSec();
  const double range = message.range;
  if (std::isnan(range) || range > message.max_range) {
    s.range = std::numeric_limits<double>::infinity();
  } else if (range < message.min_range) {
    s.range = -std::numeric_limits<double>::infinity();
  } else {
    s.range = range;
  }
  return s;
}

std::vector<ImuSample> readImuTopic(const std::string& bag_path, const std::string& topic) {
  // Messages without an orientation (a raw IMU) give nothing to level frames with: left out.
  std::vector<ImuSample> samples = readTopic<sensor_msgs::Imu, ImuSample>(bag_path, topic, [](const sensor_msgs::Imu& m) {
    ImuSample s = imuSample(m);
    if (!hasOrientation(m)) s.stamp = std::numeric_limits<double>::quiet_NaN();
    return s;
  });
  samples.erase(std::remove_if(samples.begin(), samples.end(), [](const ImuSample& s) { return std::isnan(s.stamp); }),
                samples.end());
  return samples;
}

std::vector<RangeSample> readRangeTopic(const std::string& bag_path, const std::string& topic) {
  return readTopic<sensor_msgs::Range, RangeSample>(bag_path, topic,
                                                    [](const sensor_msgs::Range& m) { return rangeSample(m); });
}

namespace {

template <typename Message>
bool frameIdOf(const rosbag::MessageInstance& instance, std::string& frame_id) {
  const auto message = instance.instantiate<Message>();
  if (!message) return false;
  frame_id = message->header.frame_id;
  return true;
}

}  // namespace

std::string firstFrameId(const std::string& bag_path, const std::string& topic) {
  if (topic.empty()) return {};
  try {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
    rosbag::View view(bag, rosbag::TopicQuery(topic));
    for (const rosbag::MessageInstance& instance : view) {
      std::string frame_id;
      if (frameIdOf<sensor_msgs::Imu>(instance, frame_id) || frameIdOf<sensor_msgs::Image>(instance, frame_id) ||
          frameIdOf<sensor_msgs::CompressedImage>(instance, frame_id) ||
          frameIdOf<sensor_msgs::Range>(instance, frame_id)) {
        return frame_id;
      }
      return {};
    }
  } catch (const rosbag::BagException& e) {
    throw BagError("cannot read bag '" + bag_path + "': " + e.what());
  }
  return {};
}

std::optional<Eigen::Quaterniond> staticRotation(const std::string& bag_path, const std::string& target,
                                                 const std::string& source, std::string& why) {
  why.clear();
  if (target.empty() || source.empty()) {
    why = "a frame id is empty";
    return std::nullopt;
  }
  if (target == source) return Eigen::Quaterniond::Identity();
  tf2::BufferCore buffer;
  std::size_t transforms = 0;
  try {
    rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
    rosbag::View view(bag, rosbag::TopicQuery("/tf_static"));
    for (const rosbag::MessageInstance& instance : view) {
      const auto message = instance.instantiate<tf2_msgs::TFMessage>();
      if (!message) continue;
      for (const geometry_msgs::TransformStamped& t : message->transforms) {
        buffer.setTransform(t, "bag", true);
        ++transforms;
      }
    }
  } catch (const rosbag::BagException& e) {
    throw BagError("cannot read bag '" + bag_path + "': " + e.what());
  }
  if (transforms == 0) {
    why = "the bag has no /tf_static";
    return std::nullopt;
  }
  try {
    const geometry_msgs::TransformStamped t = buffer.lookupTransform(target, source, ros::Time(0));
    const auto& q = t.transform.rotation;
    return Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized();
  } catch (const tf2::TransformException& e) {
    why = e.what();
    return std::nullopt;
  }
}

geometry_msgs::TransformStamped staticTransform(const std::string& parent, const std::string& child, double stamp,
                                                double qx, double qy, double qz, double qw) {
  geometry_msgs::TransformStamped transform;
  transform.header.stamp = rosStamp(stamp);
  transform.header.frame_id = parent;
  transform.child_frame_id = child;
  transform.transform.rotation.x = qx;
  transform.transform.rotation.y = qy;
  transform.transform.rotation.z = qz;
  transform.transform.rotation.w = qw;
  return transform;
}

}  // namespace oefmt
