// SPDX-License-Identifier: GPL-3.0-or-later
// The ROS face of the estimator: parameters, subscriptions, a worker thread, publishers.
// Shared by the nodelet (oefmt/OdometryNodelet) and the standalone node (oefmt_node); it adds
// nothing numeric of its own.
#pragma once

#include <atomic>
#include <condition_variable>
#include <deque>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include <diagnostic_updater/diagnostic_updater.h>
#include <diagnostic_updater/update_functions.h>
#include <image_geometry/pinhole_camera_model.h>
#include <image_transport/image_transport.h>
#include <nav_msgs/Path.h>
#include <ros/ros.h>
#include <sensor_msgs/CameraInfo.h>
#include <sensor_msgs/CompressedImage.h>
#include <sensor_msgs/Image.h>
#include <sensor_msgs/Imu.h>
#include <sensor_msgs/Range.h>
#include <std_msgs/Header.h>
#include <std_srvs/Empty.h>
#include <tf2_ros/buffer.h>
#include <tf2_ros/transform_broadcaster.h>
#include <tf2_ros/transform_listener.h>

#include "oefmt/estimation/estimator.h"
#include "oefmt/estimation/attitude.h"
#include "oefmt/estimation/estimator_config.h"
#include "oefmt/estimation/range_gate.h"
#include "oefmt/io/nadir_view.h"
#include "oefmt/io/vehicle_data.h"
#include "oefmt/ros/frame_queue.h"
#include "oefmt/ros/node_parameters.h"
#include "oefmt/ros/stamp_guard.h"
#include "oefmt/io/undistortion.h"

namespace oefmt {

class OdometryRos {
 public:
  /// Reads and validates the parameters (a bad value is fatal, naming the parameter),
  /// subscribes and starts the worker thread.
  OdometryRos(ros::NodeHandle nh, ros::NodeHandle private_nh, const std::string& name);
  ~OdometryRos();
  OdometryRos(const OdometryRos&) = delete;
  OdometryRos& operator=(const OdometryRos&) = delete;

 private:
  /// A frame as received: decoding happens on the worker, callbacks only store pointers.
  struct InputFrame {
    sensor_msgs::ImageConstPtr image;
    sensor_msgs::CompressedImageConstPtr compressed;
    ros::Time stamp;
    std::string frame_id;
    ros::WallTime received;
  };

  /// Reads and validates the estimator's and the node's parameters (fatal: InputError).
  void loadParameters();
  void imageCallback(const sensor_msgs::ImageConstPtr& message);
  void compressedCallback(const sensor_msgs::CompressedImageConstPtr& message);
  void cameraInfoCallback(const sensor_msgs::CameraInfoConstPtr& message);
  void altitudeCallback(const sensor_msgs::RangeConstPtr& message);
  void imuCallback(const sensor_msgs::ImuConstPtr& message);
  /// The camera's tilt at the frame (nothing without an IMU, or when it is stale).
  std::optional<CameraTilt> tiltAt(const InputFrame& frame);
  /// The IMU frame's rotation in base_frame (TF; the identity, said once, without one).
  const Eigen::Matrix3d& imuMount(const std::string& imu_frame);
  /// The camera's yaw turn from `from` to `to` by the IMU's gyro (nothing without its samples).
  std::optional<double> gyroTurn(double from, double to);
  /// The rangefinder's reading at the frame, vertical (nothing without one near the stamp).
  std::optional<double> verticalRangeAt(const InputFrame& frame, const std::optional<CameraTilt>& tilt);
  /// Where the rangefinder (aligned with the camera) reads in the working frame, levelled with the
  /// camera's `tilt` [px from its centre]: zero when the frame was not levelled.
  cv::Point2d beamAt(const std::optional<CameraTilt>& tilt) const;
  bool resetService(std_srvs::Empty::Request& request, std_srvs::Empty::Response& response);
  /// Stamps the frame from its message header and hands it to the worker.
  void enqueue(InputFrame frame, const std_msgs::Header& header);
  void workerLoop();
  void process(const InputFrame& frame);
  bool prepareEstimator(const InputFrame& frame, const cv::Mat& image);
  cv::Mat decode(const InputFrame& frame);
  /// Sets up undistorter_ for this calibration and image size unless it already is; throws
  /// InputError (naming `source`) when the calibration cannot be used.
  void updateUndistorter(const CameraParameters& calibration, const std::string& source, cv::Size image_size);
  void lookUpCameraMount(const InputFrame& frame);
  void publish(const InputFrame& frame, const Estimate& estimate);
  void publishDebugImages(const InputFrame& frame, const Estimate& estimate);
  void resetEstimator(const std::string& why);
  void diagnose(diagnostic_updater::DiagnosticStatusWrapper& status);

  ros::NodeHandle nh_, private_nh_;
  std::string name_;
  RosParameters parameters_;
  EstimatorConfig estimator_config_;

  image_transport::ImageTransport image_transport_;
  image_transport::Subscriber image_subscriber_;
  ros::Subscriber compressed_subscriber_, camera_info_subscriber_, altitude_subscriber_, imu_subscriber_;
  ros::Publisher odometry_publisher_, path_publisher_, energy_publisher_;
  image_transport::Publisher energy_image_publisher_, rotation_zoom_publisher_,
      translation_publisher_;
  ros::ServiceServer reset_server_;
  tf2_ros::TransformBroadcaster tf_broadcaster_;
  tf2_ros::Buffer tf_buffer_;
  tf2_ros::TransformListener tf_listener_;

  // Camera model: guarded by camera_mutex_ (written by callbacks, read by the worker).
  std::mutex camera_mutex_;
  std::condition_variable camera_ready_;
  sensor_msgs::CameraInfoConstPtr camera_info_;
  std::optional<double> altitude_from_topic_;
  // The IMU's orientations and the rangefinder's recent readings: guarded by vehicle_mutex_.
  std::mutex vehicle_mutex_;
  AttitudeHistory attitudes_;
  double imu_orientation_variance_ = 0.0;  ///< roll and pitch variance the IMU reports [rad^2]
  std::vector<RangeSample> ranges_;  ///< the latest readings, oldest first (bounded)

  // Worker state (worker thread only).
  FrameQueue<InputFrame> queue_;
  std::thread worker_;
  std::unique_ptr<Estimator> estimator_;
  StampGuard stamp_guard_;
  nav_msgs::Path path_;
  std::optional<Pose4> previous_pose_;
  double mount_yaw_ = 0.0;  ///< yaw of the camera body (x = image right) in base_frame, from TF
  Eigen::Matrix3d mount_ = downLookingMount();  ///< the optical frame in base_frame, from TF
  std::unique_ptr<const NadirView> nadir_;       ///< levels tilted frames (with undistorter_)
  RangeAltitude range_altitude_;
  /// The first frames' readings, until they settle which layer the rangefinder saw (rangeScale).
  std::vector<RangeObservation> scale_votes_;
  int scale_frames_ = 0;
  bool scale_settled_ = false;
  std::optional<CameraTilt> body_tilt_;          ///< base_frame's roll and pitch at the last frame
  std::atomic<long> unlevelled_{0};              ///< frames taken as level for want of an attitude
  std::atomic<long> levelled_{0};                ///< frames levelled with the IMU's attitude
  /// Where the scale comes from, for the diagnostics (set when the estimator is made).
  std::atomic<const char*> scale_source_{"none yet (no odometry)"};
  bool frame_unlevelled_ = false;  ///< the current frame: taken as level although the IMU had spoken
  std::string imu_frame_;           ///< the IMU messages' frame id
  std::deque<ImuSample> recent_imu_;  ///< the IMU's last samples, for the gyro's turns
  double previous_stamp_ = -1.0;      ///< of the frame last given to the estimator
  std::string imu_mount_frame_;     ///< the frame imu_mount_ was looked up for
  Eigen::Matrix3d imu_mount_ = Eigen::Matrix3d::Identity();  ///< the IMU's frame in base_frame, from TF
  double largest_tilt_ = 0.0;      ///< base_frame's largest tilt the IMU gave at a frame [rad]
  cv::Size input_size_;
  double estimator_fx_ = 0.0;
  std::unique_ptr<const Undistorter> undistorter_;  ///< of the current calibration and image size
  image_geometry::PinholeCameraModel working_camera_;  ///< rectifies undistorter_'s working frames
  /// The last calibration that could not be set up, so that it is reported, not retried, per frame.
  struct FailedCamera {
    CameraParameters calibration;
    cv::Size image_size;
    std::string error;
    bool madeFor(const CameraParameters& c, cv::Size size) const {
      return size == image_size && sameCamera(c, calibration);
    }
  };
  std::optional<FailedCamera> failed_camera_;
  std::atomic<bool> reset_requested_{false};

  // Counters for diagnostics (atomics: written by callbacks and worker, read by the updater).
  diagnostic_updater::Updater updater_;
  std::atomic<long> frames_in_{0}, frames_out_{0}, frames_dropped_{0}, frames_rejected_{0},
      optimizer_failures_{0}, registration_failures_{0};
  std::atomic<double> last_processing_ms_{0.0}, last_confidence_{1.0}, last_latency_ms_{0.0};
  std::mutex diagnostics_mutex_;
  std::string last_problem_;
  std::deque<double> recent_latencies_ms_;  ///< receipt -> publish of the last frames (bounded)
  double min_rate_, max_rate_;
  std::unique_ptr<diagnostic_updater::FrequencyStatus> input_rate_, output_rate_;
  ros::Timer diagnostics_timer_;
};

}  // namespace oefmt
