// SPDX-License-Identifier: GPL-3.0-or-later
// A vehicle's other sensors beside the camera, as a dataset folder holds them in text files
// (one sample per line, '#' comments; the same stamps as timestamps.txt):
//
//   imu.txt    t qx qy qz qw wx wy wz ax ay az
//              orientation of the body (base_link) in the world (REP-103, z up; only its roll
//              and pitch are used, a magnetometer-free yaw may drift), angular velocity [rad/s]
//              and specific force [m/s^2, +9.81 on z when level and still], both in the body frame
//   range.txt  t range
//              distance [m] along the body's down axis (-z) to the surface below; inf: no return
//              (out of range or a dropout, as REP-117 has it)
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "oefmt/estimation/attitude.h"

namespace oefmt {

struct ImuSample {
  double stamp = 0.0;  ///< [s]
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< body to world
  Eigen::Vector3d angular_velocity = Eigen::Vector3d::Zero();       ///< body frame [rad/s]
  Eigen::Vector3d linear_acceleration = Eigen::Vector3d::Zero();    ///< specific force, body frame [m/s^2]
};

struct RangeSample {
  double stamp = 0.0;  ///< [s]
  double range = 0.0;  ///< [m]; +inf: no return
};

/// The reading nearest `stamp` if within `tolerance` [s] of it (any value, +inf included).
std::optional<RangeSample> rangeAt(const std::vector<RangeSample>& readings, double stamp, double tolerance);

/// The reading nearest `stamp` (within `tolerance` [s]) turned vertical with the camera's tilt
/// (level without one): the depth of the surface below. Nothing without a reading there or when
/// it had no return.
std::optional<double> verticalRange(const std::vector<RangeSample>& readings, double stamp, double tolerance,
                                    const std::optional<CameraTilt>& tilt);

/// The file names inside a dataset folder.
constexpr const char* kImuFileName = "imu.txt";
constexpr const char* kRangeFileName = "range.txt";

/// Read and written as documented above. Readers throw DatasetError naming the file and line for
/// a line that is not the expected numbers, a non-finite value (a range may be +inf), a zero
/// quaternion, or stamps that do not increase; writers throw DatasetError when they cannot write.
std::vector<ImuSample> readImuFile(const std::string& path);
void writeImuFile(const std::string& path, const std::vector<ImuSample>& samples,
                  const std::vector<std::string>& header = {});
std::vector<RangeSample> readRangeFile(const std::string& path);
void writeRangeFile(const std::string& path, const std::vector<RangeSample>& samples,
                    const std::vector<std::string>& header = {});

}  // namespace oefmt
