// SPDX-License-Identifier: GPL-3.0-or-later
// Trajectories in the TUM format ("t x y z qx qy qz qw" per line), read and written.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "oefmt/estimation/attitude.h"
#include "oefmt/estimation/pose.h"

namespace oefmt {

/// One pose of a trajectory: time [s], position [m], orientation (body to world).
struct StampedPose {
  double stamp = 0.0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();
};
/// A trajectory as TUM files hold it (ground truth, an estimate read back).
using StampedTrajectory = std::vector<StampedPose>;

/// Reads a TUM file (`t x y z qx qy qz qw` per line; '#' comments and blank lines skipped;
/// commas are accepted as separators). Throws DatasetError naming the file and line.
StampedTrajectory readTum(const std::string& path);

/// Writes a TUM file; `header` lines are written first, each prefixed with "# ".
/// Throws DatasetError when the file cannot be written.
void writeTum(const std::string& path, const StampedTrajectory& trajectory,
              const std::vector<std::string>& header = {});

/// One TUM line "t x y z qx qy qz qw" (no newline) of an estimated pose, at full double
/// precision (the offline runner writes its trajectory line by line, so nothing is lost when a
/// run stops early).
std::string toTumLine(const Pose4& pose);
/// The same with the camera body's roll and pitch (from an IMU): a 6-DOF pose.
std::string toTumLine(const Pose4& pose, const CameraTilt& tilt);

}  // namespace oefmt
