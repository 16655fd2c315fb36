// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/ros/odometry_ros.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <cv_bridge/cv_bridge.h>
#include <geometry_msgs/TransformStamped.h>
#include <nav_msgs/Odometry.h>
#include <opencv2/imgproc.hpp>
#include <ros/package.h>
#include <tf2/LinearMath/Matrix3x3.h>
#include <tf2/LinearMath/Quaternion.h>

#include "oefmt/EnergyVectors.h"
#include "oefmt/io/config_file.h"
#include "oefmt/error.h"
#include "oefmt/registration/image_prep.h"
#include "oefmt/ros/bag_io.h"
#include "oefmt/ros/estimate_messages.h"
#include "oefmt/ros/vehicle_messages.h"
#include "oefmt/ros/parameter_server.h"
#include "oefmt/estimation/pose.h"
#include "oefmt/io/undistortion.h"
#include "oefmt/io/fft_wisdom.h"
#include "oefmt/io/run_setup.h"
#include "oefmt/ros/rectification.h"

namespace oefmt {
namespace {

constexpr double kWarnPeriod = 5.0;  // [s] between repeats of a per-frame warning
constexpr size_t kLatencyWindow = 200;  // frames in the latency statistics

}  // namespace

OdometryRos::OdometryRos(ros::NodeHandle nh, ros::NodeHandle private_nh, const std::string& name)
    : nh_(nh),
      private_nh_(private_nh),
      name_(name),
      image_transport_(nh),
      tf_listener_(tf_buffer_) {
  useDefaultFftWisdom();
  loadParameters();
  stamp_guard_ = StampGuard(parameters_.time_jump_tolerance);
  ROS_INFO_STREAM(name_ << ": effective estimator configuration:\n" << configToYaml(estimator_config_));
  {
    // Plan the FFTs now (FFTW keeps what it measured for later plans of the same size): the
    // first frame must not stall the stream for the seconds planning takes.
    const RegistrationConfig& registration = estimator_config_.registration;
    const std::string notice = fftPlanningNotice(registration);
    if (!notice.empty()) ROS_INFO_STREAM(name_ << ": " << notice);
    const SpectralContext warm_up(registration);
  }

  odometry_publisher_ = nh_.advertise<nav_msgs::Odometry>("odom", 20);
  if (parameters_.path_length > 0) path_publisher_ = nh_.advertise<nav_msgs::Path>("path", 2);
  energy_publisher_ = nh_.advertise<oefmt::EnergyVectors>("energy_vectors", 10);
  energy_image_publisher_ = image_transport_.advertise("debug/energy_vectors", 1);
  rotation_zoom_publisher_ = image_transport_.advertise("debug/rotation_zoom_psd", 1);
  translation_publisher_ = image_transport_.advertise("debug/translation_psd", 1);
  reset_server_ = private_nh_.advertiseService("reset", &OdometryRos::resetService, this);

  updater_.setHardwareID(name_);
  min_rate_ = parameters_.min_rate;
  max_rate_ = parameters_.max_rate;
  input_rate_ = std::make_unique<diagnostic_updater::FrequencyStatus>(
      diagnostic_updater::FrequencyStatusParam(&min_rate_, &max_rate_, 0.1, 10), "input rate");
  output_rate_ = std::make_unique<diagnostic_updater::FrequencyStatus>(
      diagnostic_updater::FrequencyStatusParam(&min_rate_, &max_rate_, 0.1, 10), "odometry rate");
  updater_.add(*input_rate_);
  updater_.add(*output_rate_);
  updater_.add("odometry", this, &OdometryRos::diagnose);
  diagnostics_timer_ = nh_.createTimer(ros::Duration(parameters_.diagnostics_period),
                                       [this](const ros::TimerEvent&) { updater_.update(); });

  camera_info_subscriber_ =
      nh_.subscribe("camera_info", parameters_.queue_size, &OdometryRos::cameraInfoCallback, this);
  if (parameters_.use_altitude_topic || parameters_.use_range) {
    altitude_subscriber_ = nh_.subscribe("altitude", 20, &OdometryRos::altitudeCallback, this);
  }
  if (parameters_.use_imu) {
    attitudes_ = AttitudeHistory(parameters_.imu_timeout);
    imu_subscriber_ = nh_.subscribe("imu", 400, &OdometryRos::imuCallback, this);
  }
  queue_.setCapacity(static_cast<std::size_t>(parameters_.input_buffer));
  worker_ = std::thread(&OdometryRos::workerLoop, this);
  if (parameters_.compressed) {
    // Debian packages no compressed image_transport plugin: decode CompressedImage ourselves.
    compressed_subscriber_ = nh_.subscribe(nh_.resolveName("image") + "/compressed",
                                           parameters_.queue_size,
                                           &OdometryRos::compressedCallback, this);
  } else {
    image_subscriber_ = image_transport_.subscribe(
        "image", parameters_.queue_size, &OdometryRos::imageCallback, this,
        image_transport::TransportHints("raw", ros::TransportHints(), private_nh_));
  }
  ROS_INFO_STREAM(name_ << ": listening on " << nh_.resolveName("image")
                        << (parameters_.compressed ? "/compressed" : "") << ", publishing "
                        << nh_.resolveName("odom") << " (" << parameters_.odom_frame << " -> "
                        << parameters_.base_frame << ")");
}

OdometryRos::~OdometryRos() {
  queue_.shutdown();
  if (worker_.joinable()) worker_.join();
}

void OdometryRos::loadParameters() {
  // The configuration file, loaded into the private namespace by the launch file, and the node's
  // own parameters share that namespace: both tables are read from it in one pass. Keys not
  // given keep their defaults; a bad value is fatal, naming the parameter.
  try {
    ParameterTable table = estimatorParameters(estimator_config_);
    const ParameterTable node = nodeParameters(parameters_);
    table.insert(table.end(), node.begin(), node.end());
    const std::vector<std::string> others = readParameterServer(private_nh_, table);
    for (const std::string& other : others) {
      ROS_WARN_STREAM(name_ << ": parameter " << private_nh_.resolveName(other)
                            << " is neither the node's nor the estimator's: ignored (see doc/parameters.md)");
    }
    estimator_config_.validate();
    parameters_.validate();
  } catch (const InputError& e) {
    const std::string message = name_ + ": " + e.what();
    ROS_FATAL_STREAM(message);
    throw InputError(message);
  }
}

void OdometryRos::imageCallback(const sensor_msgs::ImageConstPtr& message) {
  InputFrame frame;
  frame.image = message;
  enqueue(std::move(frame), message->header);
}

void OdometryRos::compressedCallback(const sensor_msgs::CompressedImageConstPtr& message) {
  InputFrame frame;
  frame.compressed = message;
  enqueue(std::move(frame), message->header);
}

void OdometryRos::enqueue(InputFrame frame, const std_msgs::Header& header) {
  frame.stamp = header.stamp;
  frame.frame_id = header.frame_id;
  frame.received = ros::WallTime::now();
  ++frames_in_;
  input_rate_->tick();
  if (queue_.put(std::move(frame))) {
    ++frames_dropped_;
    ROS_WARN_STREAM_THROTTLE(kWarnPeriod, name_ << ": frames arrive faster than they are processed;"
                                               " the newest wins (" << frames_dropped_.load()
                                               << " dropped so far; ~input_buffer absorbs bursts)");
  }
}

void OdometryRos::cameraInfoCallback(const sensor_msgs::CameraInfoConstPtr& message) {
  {
    std::lock_guard<std::mutex> lock(camera_mutex_);
    camera_info_ = message;
  }
  camera_ready_.notify_all();
}

void OdometryRos::altitudeCallback(const sensor_msgs::RangeConstPtr& message) {
  if (!std::isfinite(message->range) || message->range < message->min_range ||
      message->range > message->max_range) {
    return;  // no return (REP-117's +inf), too close, or invalid
  }
  {
    std::lock_guard<std::mutex> lock(vehicle_mutex_);
    ranges_.push_back({message->header.stamp.toSec(), message->range});
    constexpr std::size_t kKeptReadings = 50;
    if (ranges_.size() > kKeptReadings) ranges_.erase(ranges_.begin());
  }
  {
    std::lock_guard<std::mutex> lock(camera_mutex_);
    altitude_from_topic_ = message->range;
  }
  camera_ready_.notify_all();
}

void OdometryRos::imuCallback(const sensor_msgs::ImuConstPtr& message) {
  if (!hasOrientation(*message)) {
    ROS_WARN_STREAM_THROTTLE(kWarnPeriod, name_ << ": " << nh_.resolveName("imu")
                                                << " has no orientation: frames are taken as level");
    return;
  }
  const ImuSample sample = imuSample(*message);
  std::lock_guard<std::mutex> lock(vehicle_mutex_);
  imu_frame_ = message->header.frame_id;
  // Frames older than kImuKept are long processed.
  constexpr double kImuKept = 10.0;  // [s]
  if (recent_imu_.empty() || sample.stamp > recent_imu_.back().stamp) recent_imu_.push_back(sample);
  while (!recent_imu_.empty() && recent_imu_.front().stamp < sample.stamp - kImuKept) recent_imu_.pop_front();
  attitudes_.add(sample.stamp, sample.orientation);
  attitudes_.forgetBefore(sample.stamp - kImuKept);
  const double roll = message->orientation_covariance[0], pitch = message->orientation_covariance[4];
  imu_orientation_variance_ = std::isfinite(roll) && std::isfinite(pitch) ? std::max({roll, pitch, 0.0}) : 0.0;
}

const Eigen::Matrix3d& OdometryRos::imuMount(const std::string& imu_frame) {
  if (imu_frame == imu_mount_frame_) return imu_mount_;
  imu_mount_frame_ = imu_frame;
  imu_mount_ = Eigen::Matrix3d::Identity();
  if (imu_frame.empty() || imu_frame == parameters_.base_frame) return imu_mount_;
  try {
    const auto q = tf_buffer_.lookupTransform(parameters_.base_frame, imu_frame, ros::Time(0), ros::Duration(0.2))
                       .transform.rotation;
    imu_mount_ = Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized().toRotationMatrix();
    ROS_INFO_STREAM(name_ << ": IMU mount from TF: " << imu_frame << " in " << parameters_.base_frame);
  } catch (const tf2::TransformException& e) {
    ROS_WARN_STREAM(name_ << ": no TF " << parameters_.base_frame << " -> " << imu_frame << " (" << e.what()
                          << "): the IMU's frame is taken as " << parameters_.base_frame);
  }
  return imu_mount_;
}

std::optional<double> OdometryRos::gyroTurn(double from, double to) {
  std::vector<ImuSample> samples;
  std::string imu_frame;
  {
    std::lock_guard<std::mutex> lock(vehicle_mutex_);
    imu_frame = imu_frame_;
    for (const ImuSample& s : recent_imu_) {
      if (s.stamp >= from - parameters_.imu_timeout && s.stamp <= to + parameters_.imu_timeout) samples.push_back(s);
    }
  }
  if (samples.empty()) return std::nullopt;
  // The camera body's yaw (the level view keeps it), from the IMU's samples through the mounts.
  TurnHistory turns(parameters_.imu_timeout, imuMount(imu_frame).transpose() * mount_ * downLookingMount().transpose());
  for (const ImuSample& s : samples) turns.add(s.stamp, s.orientation, s.angular_velocity);
  return turns.turn(from, to);
}

std::optional<CameraTilt> OdometryRos::tiltAt(const InputFrame& frame) {
  frame_unlevelled_ = false;
  std::optional<Eigen::Quaterniond> body;
  std::string imu_frame;
  {
    std::lock_guard<std::mutex> lock(vehicle_mutex_);
    imu_frame = imu_frame_;
    if (attitudes_.empty()) return std::nullopt;
    const double stamp = frame.stamp.toSec();
    body = attitudes_.at(stamp);
    // The newest orientation may lag the image by less than a sample: taken when recent enough.
    if (!body && stamp >= attitudes_.newestStamp() && stamp - attitudes_.newestStamp() <= parameters_.imu_timeout) {
      body = attitudes_.at(attitudes_.newestStamp());
    }
  }
  if (!body) {
    ++unlevelled_;
    ROS_WARN_STREAM_THROTTLE(kWarnPeriod, name_ << ": no IMU orientation within " << parameters_.imu_timeout
                                                << " s of the frame: taken as level (" << unlevelled_
                                                << " frames so far)");
    body_tilt_.reset();
    frame_unlevelled_ = true;
    return std::nullopt;
  }
  // world <- base = (world <- imu)(imu <- base): base_frame's own roll and pitch, and the
  // camera's by its mount.
  const Eigen::Matrix3d base = body->toRotationMatrix() * imuMount(imu_frame).transpose();
  body_tilt_ = cameraTilt(base * downLookingMount());
  ++levelled_;
  largest_tilt_ = std::max(largest_tilt_, tiltAngle(*body_tilt_));
  return cameraTilt(base * mount_);
}

std::optional<double> OdometryRos::verticalRangeAt(const InputFrame& frame, const std::optional<CameraTilt>& tilt) {
  constexpr double kRangeMatch = 0.05;  // [s]: a reading belongs to a frame this near
  std::lock_guard<std::mutex> lock(vehicle_mutex_);
  return verticalRange(ranges_, frame.stamp.toSec(), kRangeMatch, tilt);
}

cv::Point2d OdometryRos::beamAt(const std::optional<CameraTilt>& tilt) const {
  return beamInFrame(nadir_ ? tilt : std::nullopt, estimator_fx_);  // without nadir_: taken as level
}

bool OdometryRos::resetService(std_srvs::Empty::Request&, std_srvs::Empty::Response&) {
  reset_requested_ = true;
  queue_.clear();
  ROS_INFO_STREAM(name_ << ": reset requested");
  return true;
}

void OdometryRos::workerLoop() {
  InputFrame frame;
  while (queue_.take(frame)) {
    try {
      process(frame);
    } catch (const std::exception& e) {
      // Nothing may escape the worker: count, report and go on with the next frame.
      ++frames_rejected_;
      {
        std::lock_guard<std::mutex> lock(diagnostics_mutex_);
        last_problem_ = e.what();
      }
      ROS_ERROR_STREAM_THROTTLE(kWarnPeriod, name_ << ": frame skipped: " << e.what());
    }
  }
}

void OdometryRos::resetEstimator(const std::string& why) {
  ROS_WARN_STREAM(name_ << ": restarting the odometry: " << why);
  estimator_.reset();
  stamp_guard_.reset();
  path_.poses.clear();
  previous_pose_.reset();
  input_size_ = cv::Size();
  nadir_.reset();
  range_altitude_ = RangeAltitude();
  previous_stamp_ = -1.0;
  scale_votes_.clear();
  scale_frames_ = 0;
  scale_settled_ = false;
}

cv::Mat OdometryRos::decode(const InputFrame& frame) {
  try {
    return frame.image ? imageFromMessage(*frame.image) : imageFromMessage(*frame.compressed);
  } catch (const BagError& e) {
    throw InputError(std::string("cannot use the image: ") + e.what());
  }
}

bool OdometryRos::prepareEstimator(const InputFrame& frame, const cv::Mat& image) {
  // Refused before it could restart the odometry (prepareImage's own check).
  requireRegistrableSize(image);
  if (!input_size_.empty() && image.size() != input_size_) {
    resetEstimator("the image size changed from " + std::to_string(input_size_.width) + "x" +
                   std::to_string(input_size_.height) + " to " + std::to_string(image.cols) +
                   "x" + std::to_string(image.rows));
  }
  sensor_msgs::CameraInfoConstPtr info;
  std::optional<double> altitude_topic;
  {
    // A camera driver or bag publishes image and camera_info together, but the image callback
    // may run first: give the first camera_info a moment before calling it missing.
    std::unique_lock<std::mutex> lock(camera_mutex_);
    if (!camera_info_ && !(estimator_config_.camera_fx > 0.0)) {
      camera_ready_.wait_for(lock, std::chrono::seconds(1), [this] { return camera_info_ != nullptr; });
    }
    info = camera_info_;
    // A rangefinder that publishes gives the initial altitude: its first reading may trail the
    // first image by a moment.
    if (!estimator_ && parameters_.use_range && !altitude_from_topic_ && altitude_subscriber_.getNumPublishers() > 0) {
      camera_ready_.wait_for(lock, std::chrono::milliseconds(500), [this] { return altitude_from_topic_.has_value(); });
    }
    altitude_topic = altitude_from_topic_;
  }
  // The camera of the frames as registered (set up as oefmt_offline does): camera_info's
  // calibration, or ~camera_fx, mapped to the image size, its lens distortion undone.
  CameraSources sources;
  if (info && info->K[0] > 0.0 && info->K[4] > 0.0) {
    try {
      sources.calibration = cameraFromInfo(*info);
    } catch (const BagError& e) {
      throw InputError(std::string("camera_info: ") + e.what());
    }
    sources.calibration_source = "camera_info";
  }
  sources.camera_fx = estimator_config_.camera_fx;
  sources.undistort = parameters_.undistort;
  if (const auto chosen = chooseCamera(sources, image.size())) {
    updateUndistorter(chosen->camera, chosen->source, image.size());
  } else {
    undistorter_.reset();
  }
  // The working image's focal length (the core crops to a square and resizes to N): the
  // undistortion set-up scales the camera to it.
  const double working_fx = undistorter_ ? undistorter_->workingFx() : 0.0;
  if (!(working_fx > 0.0)) {
    ROS_ERROR_STREAM_THROTTLE(kWarnPeriod, name_ << ": no intrinsics: publish "
                                                 << nh_.resolveName("camera_info")
                                                 << " (with a non-zero K) or set ~camera_fx");
    std::lock_guard<std::mutex> lock(diagnostics_mutex_);
    last_problem_ = "no camera intrinsics (camera_info missing or zero, ~camera_fx unset)";
    return false;
  }
  if (estimator_ && std::fabs(working_fx - estimator_fx_) > 1e-6 * working_fx) {
    resetEstimator("the focal length changed");
  }
  if (!estimator_) {
    EstimatorConfig config = estimator_config_;
    config.working_fx = working_fx;
    // The initial altitude: the altitude topic when asked for, else ~initial_altitude (the
    // configuration file's, or the launch argument's).
    if (parameters_.use_altitude_topic && !altitude_topic) {
      ROS_WARN_STREAM_THROTTLE(kWarnPeriod, name_ << ": waiting for a valid "
                                                  << nh_.resolveName("altitude") << " range");
      return false;
    }
    config.initial_altitude = chooseInitialAltitude(altitude_topic, config.initial_altitude);
    estimator_ = std::make_unique<Estimator>(config);
    scale_source_ = altitude_topic ? (parameters_.use_range ? "rangefinder (altitude topic), every reading"
                                                            : "rangefinder (altitude topic), its first reading")
                    : config.initial_altitude > 0.0 ? "~initial_altitude"
                                                    : "none: units of the initial altitude";
    previous_stamp_ = -1.0;
    lookUpCameraMount(frame);
    if (parameters_.use_imu) {
      nadir_ = std::make_unique<const NadirView>(undistorter_->inputCamera(), image.size(), working_fx,
                                                 config.registration.size);
    }
    estimator_fx_ = working_fx;
    input_size_ = image.size();
    ROS_INFO_STREAM(name_ << ": odometry started at " << frame.stamp << " (" << image.cols << "x"
                          << image.rows << ", working fx " << working_fx << " px, scale "
                          << (config.initial_altitude > 0.0 ? "metric" : "initial altitude = 1") << ")");
    const std::string upscaling = upscalingWarning(image.size(), config.registration.size);
    if (!upscaling.empty()) ROS_WARN_STREAM(name_ << ": " << upscaling);
  }
  return true;
}

void OdometryRos::lookUpCameraMount(const InputFrame& frame) {
  mount_yaw_ = 0.0;
  mount_ = downLookingMount();
  const std::string camera_frame =
      parameters_.camera_frame.empty() ? frame.frame_id : parameters_.camera_frame;
  if (camera_frame.empty()) return;
  geometry_msgs::TransformStamped mount;
  try {
    mount = tf_buffer_.lookupTransform(parameters_.base_frame, camera_frame, ros::Time(0),
                                       ros::Duration(0.2));
  } catch (const tf2::TransformException& e) {
    ROS_INFO_STREAM(name_ << ": no TF " << parameters_.base_frame << " -> " << camera_frame
                          << " (" << e.what() << "): " << parameters_.base_frame
                          << " is taken to be the camera body (looking straight down, x = image "
                             "right, y = image up)");
    return;
  }
  const auto& q = mount.transform.rotation;
  mount_ = Eigen::Quaterniond(q.w, q.x, q.y, q.z).normalized().toRotationMatrix();
  const tf2::Matrix3x3 optical(tf2::Quaternion(q.x, q.y, q.z, q.w));
  // Camera body = optical frame with y and z flipped (x image right, y image up, z up).
  const tf2::Matrix3x3 body = optical * tf2::Matrix3x3(1, 0, 0, 0, -1, 0, 0, 0, -1);
  const double tilt = std::acos(std::clamp(body[2][2], -1.0, 1.0));
  if (tilt > 10.0 * M_PI / 180.0) {
    ROS_WARN_STREAM(name_ << ": the camera is tilted " << tilt * 180.0 / M_PI
                          << " deg from straight down; the 4-DOF odometry assumes a level, "
                             "down-looking camera");
  }
  mount_yaw_ = std::atan2(body[1][0], body[0][0]);
  ROS_INFO_STREAM(name_ << ": camera mount from TF: yaw " << mount_yaw_ * 180.0 / M_PI
                        << " deg in " << parameters_.base_frame);
}

void OdometryRos::process(const InputFrame& frame) {
  if (reset_requested_.exchange(false)) resetEstimator("~reset was called");
  const StampGuard::Verdict verdict = stamp_guard_.check(frame.stamp.toSec());
  if (verdict == StampGuard::Verdict::kJumpBack) {
    resetEstimator("time jumped back (bag loop or restarted source)");
    stamp_guard_.check(frame.stamp.toSec());
  } else if (verdict != StampGuard::Verdict::kAccept) {
    ++frames_rejected_;
    ROS_WARN_STREAM_THROTTLE(kWarnPeriod, name_ << ": frame dropped: " << toString(verdict) << " ("
                                               << frame.stamp << ")");
    return;
  }
  cv::Mat image = decode(frame);
  if (!prepareEstimator(frame, image)) {
    ++frames_rejected_;
    return;
  }
  // A tilted frame becomes a level camera's view (lens undone in the same step); else the
  // rectification of the working frame.
  const std::optional<CameraTilt> tilt = parameters_.use_imu ? tiltAt(frame) : std::nullopt;
  const bool levelled = tilt && nadir_;
  PreparedImage level_view;
  if (levelled) {
    level_view = nadir_->prepare(image, nadirFromOptical(*tilt));
  } else if (undistorter_) {
    image = rectifyToWorkingFrame(*undistorter_, working_camera_, image);
  }
  // Correlation surfaces cost copies: only while someone watches them.
  estimator_->setKeepSurfaces(rotation_zoom_publisher_.getNumSubscribers() > 0 ||
                              translation_publisher_.getNumSubscribers() > 0);
  // The gyro's turn since the previous frame: the rotation the registration searches around.
  if (parameters_.use_imu && previous_stamp_ >= 0.0) {
    if (const std::optional<double> turn = gyroTurn(previous_stamp_, frame.stamp.toSec())) {
      estimator_->setTurn(*turn, kGyroRateError * (frame.stamp.toSec() - previous_stamp_));
    }
  }
  if (levelled) estimator_->setLevelled();
  const auto start = std::chrono::steady_clock::now();
  const std::optional<Estimate> estimate =
      levelled ? estimator_->push(level_view, frame.stamp.toSec()) : estimator_->push(image, frame.stamp.toSec());
  if (estimate) previous_stamp_ = frame.stamp.toSec();
  last_processing_ms_ =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (!estimate) return;
  if (parameters_.use_range && estimator_->config().initial_altitude > 0.0 && !scale_settled_) {
    // The initial altitude was the first reading, whichever surface it saw; the first frames'
    // readings and depth layers then vote which one it was (as oefmt_offline does ahead), and the
    // odometry is rescaled once (it jumps then, by the vote's factor). Before that no reading is
    // used.
    const std::optional<double> vertical = verticalRangeAt(frame, body_tilt_);
    if (vertical && estimate->state == TrackingState::kTracking) {
      scale_votes_.push_back(rangeObservation(*estimator_, *estimate, *vertical, beamAt(tilt)));
    }
    if (++scale_frames_ >= static_cast<int>(kRangeVoteFrames)) {
      scale_settled_ = true;
      if (const std::optional<double> factor = rangeScale(scale_votes_)) {
        // The first frames were integrated at the first reading's scale: all of it, and the last
        // pose and the path published (so that the next twist is not a jump), at the voted one.
        estimator_->rescale(*factor);
        if (previous_pose_) previous_pose_ = rescaled(*previous_pose_, *factor);
        for (geometry_msgs::PoseStamped& p : path_.poses) {
          p.pose.position.x *= *factor;
          p.pose.position.y *= *factor;
          p.pose.position.z *= *factor;
        }
        ROS_INFO_STREAM(name_ << ": scale from the rangefinder: the first readings fit a reference plane "
                              << estimator_->altitude() << " m below (the odometry so far times " << *factor
                              << ")");
      }
      scale_votes_.clear();
    }
  } else if (parameters_.use_range && estimator_->config().initial_altitude > 0.0) {
    if (range_altitude_.update(*estimator_, *estimate, verticalRangeAt(frame, body_tilt_), beamAt(tilt))) {
      Estimate corrected = *estimate;
      corrected.pose = estimator_->pose();
      publish(frame, corrected);
      return;
    }
  }
  publish(frame, *estimate);
}

void OdometryRos::updateUndistorter(const CameraParameters& calibration, const std::string& source,
                                    cv::Size image_size) {
  if (undistorter_ && undistorter_->madeFor(calibration, image_size)) return;
  if (failed_camera_ && failed_camera_->madeFor(calibration, image_size)) {
    throw InputError(failed_camera_->error);  // the same calibration again: not set up again
  }
  // Set up once per calibration and image size (finding the working frame takes a few
  // milliseconds).
  undistorter_.reset();
  try {
    undistorter_ = std::make_unique<const Undistorter>(calibration, image_size,
                                                       estimator_config_.registration.size, source);
    failed_camera_.reset();
  } catch (const InputError& e) {
    failed_camera_ = FailedCamera{calibration, image_size, e.what()};
    ROS_ERROR_STREAM(name_ << ": " << failed_camera_->error);
    throw;
  }
  // image_geometry makes (and keeps) the maps of this working frame.
  if (undistorter_->remaps()) working_camera_.fromCameraInfo(workingFrameInfo(*undistorter_));
  for (const std::string& note : undistorter_->notes()) ROS_INFO_STREAM(name_ << ": " << note);
}

void OdometryRos::publish(const InputFrame& frame, const Estimate& estimate) {
  if (!estimate.pose.finite()) {
    // The estimator never returns NaN; if it ever did, nothing of it may leave the node.
    ++registration_failures_;
    ROS_ERROR_STREAM_THROTTLE(kWarnPeriod, name_ << ": non-finite pose withheld at " << frame.stamp);
    return;
  }
  const Pose4 pose = rotatedPose(estimate.pose, mount_yaw_);
  std_msgs::Header header;
  header.stamp = frame.stamp;
  header.frame_id = parameters_.odom_frame;
  const Pose4* previous = previous_pose_ ? &*previous_pose_ : nullptr;
  nav_msgs::Odometry odometry = odometryMessage(pose, previous, header, parameters_.base_frame);
  geometry_msgs::TransformStamped transform = transformMessage(pose, header, parameters_.base_frame);
  if (body_tilt_) {
    // 6-DOF: roll and pitch from the IMU (observed, with its variance), x, y, z and yaw from the
    // images.
    const Eigen::Quaterniond q = cameraBodyOrientation(pose.yaw, *body_tilt_);
    for (geometry_msgs::Quaternion* out : {&odometry.pose.pose.orientation, &transform.transform.rotation}) {
      out->x = q.x();
      out->y = q.y();
      out->z = q.z();
      out->w = q.w();
    }
    constexpr double kDefaultTiltVariance = 0.5 * M_PI / 180.0 * 0.5 * M_PI / 180.0;
    const double variance = imu_orientation_variance_ > 0.0 ? imu_orientation_variance_ : kDefaultTiltVariance;
    odometry.pose.covariance[3 * 6 + 3] = variance;
    odometry.pose.covariance[4 * 6 + 4] = variance;
  } else if (frame_unlevelled_) {
    // The IMU went quiet and the frame was taken as level: its tilt, up to the largest the
    // vehicle showed, is in the position and unknown in roll and pitch.
    std::array<double, 36> covariance;
    std::copy(odometry.pose.covariance.begin(), odometry.pose.covariance.end(), covariance.begin());
    addUnknownTilt(covariance, estimator_->altitude(), largest_tilt_);
    std::copy(covariance.begin(), covariance.end(), odometry.pose.covariance.begin());
  }
  odometry_publisher_.publish(odometry);
  previous_pose_ = pose;
  if (parameters_.publish_tf) tf_broadcaster_.sendTransform(transform);
  if (parameters_.path_length > 0) {
    geometry_msgs::PoseStamped stamped;
    stamped.header = header;
    stamped.pose.position.x = pose.x;
    stamped.pose.position.y = pose.y;
    stamped.pose.position.z = pose.z;
    stamped.pose.orientation = odometry.pose.pose.orientation;  // with the IMU's roll and pitch
    path_.header = header;
    path_.poses.push_back(stamped);
    if (static_cast<int>(path_.poses.size()) > parameters_.path_length) {
      path_.poses.erase(path_.poses.begin(),
                        path_.poses.begin() + (path_.poses.size() - parameters_.path_length));
    }
    path_publisher_.publish(path_);
  }
  if (energy_publisher_.getNumSubscribers() > 0) {
    energy_publisher_.publish(energyVectorsMessage(estimate, estimator_->logZoomPerBin(),
                                                   estimator_->shiftPerBin(), header));
  }
  publishDebugImages(frame, estimate);

  ++frames_out_;
  output_rate_->tick();
  last_confidence_ = estimate.registration12.confidence;
  if (estimate.loop.status == OptimizerStatus::kFallback) ++optimizer_failures_;
  if (estimate.state == TrackingState::kPredicted || estimate.state == TrackingState::kHeld ||
      estimate.state == TrackingState::kRestarted) {
    ++registration_failures_;
  }
  last_latency_ms_ = (ros::WallTime::now() - frame.received).toSec() * 1e3;
  std::lock_guard<std::mutex> lock(diagnostics_mutex_);
  recent_latencies_ms_.push_back(last_latency_ms_);
  if (recent_latencies_ms_.size() > kLatencyWindow) recent_latencies_ms_.pop_front();
}

void OdometryRos::publishDebugImages(const InputFrame& frame, const Estimate& estimate) {
  std_msgs::Header header;
  header.stamp = frame.stamp;
  header.frame_id = frame.frame_id;
  if (energy_image_publisher_.getNumSubscribers() > 0) {
    const cv::Mat plot = renderEnergyVectors(estimate, estimator_->shiftPerBin());
    energy_image_publisher_.publish(cv_bridge::CvImage(header, "bgr8", plot).toImageMsg());
  }
  if (!estimate.surfaces12) return;
  const RegistrationSurfaces& surfaces = *estimate.surfaces12;
  if (rotation_zoom_publisher_.getNumSubscribers() > 0 && !surfaces.rotation_zoom.empty()) {
    rotation_zoom_publisher_.publish(
        cv_bridge::CvImage(header, "bgr8", renderSurface(surfaces.rotation_zoom)).toImageMsg());
  }
  if (translation_publisher_.getNumSubscribers() > 0 && !surfaces.translation.empty()) {
    translation_publisher_.publish(
        cv_bridge::CvImage(header, "bgr8", renderSurface(surfaces.translation)).toImageMsg());
  }
}

void OdometryRos::diagnose(diagnostic_updater::DiagnosticStatusWrapper& status) {
  std::string problem;
  std::vector<double> latencies;
  {
    std::lock_guard<std::mutex> lock(diagnostics_mutex_);
    problem = last_problem_;
    latencies.assign(recent_latencies_ms_.begin(), recent_latencies_ms_.end());
  }
  std::sort(latencies.begin(), latencies.end());
  const long in = frames_in_, out = frames_out_;
  if (in > 0 && out == 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::ERROR,
                   problem.empty() ? "frames arrive but no odometry is published" : problem);
  } else if (last_confidence_ < estimator_config_.registration.min_confidence && out > 0) {
    status.summary(diagnostic_msgs::DiagnosticStatus::WARN, "low registration confidence");
  } else {
    status.summary(diagnostic_msgs::DiagnosticStatus::OK, out > 0 ? "tracking" : "waiting for images");
  }
  status.add("frames received", in);
  status.add("odometry published", out);
  status.add("frames dropped (newest wins)", frames_dropped_.load());
  status.add("frames rejected (stamp, encoding, intrinsics)", frames_rejected_.load());
  status.add("frames not registered (pose predicted or held)", registration_failures_.load());
  status.add("optimizer fallbacks", optimizer_failures_.load());
  status.add("processing time of the last frame [ms]", last_processing_ms_.load());
  status.add("latency of the last frame [ms]", last_latency_ms_.load());
  if (!latencies.empty()) {
    // Receipt of the image to publication of its odometry, over the last frames.
    status.add("latency median [ms]", latencies[latencies.size() / 2]);
    status.add("latency 95th percentile [ms]", latencies[latencies.size() * 95 / 100]);
  }
  status.add("registration confidence", last_confidence_.load());
  status.add("mode", toString(estimator_config_.mode));
  status.add("scale source", scale_source_.load());
  status.add("frames levelled with the IMU", levelled_.load());
  status.add("frames taken as level (IMU stale)", unlevelled_.load());
  if (!problem.empty()) status.add("last problem", problem);
}

}  // namespace oefmt
