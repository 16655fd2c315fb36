// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/io/tum.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "oefmt/io/dataset.h"

namespace oefmt {

StampedTrajectory readTum(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw DatasetError("cannot open trajectory '" + path + "'");
  StampedTrajectory trajectory;
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    std::replace(line.begin(), line.end(), ',', ' ');
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    std::istringstream fields(line);
    double v[8];
    int read = 0;
    while (read < 8 && fields >> v[read]) ++read;
    if (read != 8) {
      throw DatasetError("'" + path + "' line " + std::to_string(number) +
                         ": expected 8 numbers 't x y z qx qy qz qw'");
    }
    StampedPose pose;
    pose.stamp = v[0];
    pose.position = Eigen::Vector3d(v[1], v[2], v[3]);
    pose.orientation = Eigen::Quaterniond(v[7], v[4], v[5], v[6]);
    const double norm = pose.orientation.norm();
    if (!std::isfinite(norm) || norm < 1e-9 || !pose.position.allFinite() || !std::isfinite(pose.stamp)) {
      throw DatasetError("'" + path + "' line " + std::to_string(number) + ": invalid pose");
    }
    pose.orientation.normalize();
    trajectory.push_back(pose);
  }
  return trajectory;
}

void writeTum(const std::string& path, const StampedTrajectory& trajectory,
              const std::vector<std::string>& header) {
  std::FILE* file = std::fopen(path.c_str(), "w");
  if (!file) throw DatasetError("cannot write trajectory '" + path + "'");
  for (const std::string& line : header) std::fprintf(file, "# %s\n", line.c_str());
  for (const StampedPose& p : trajectory) {
    const Eigen::Quaterniond& q = p.orientation;
    std::fprintf(file, "%.6f %.6f %.6f %.6f %.9f %.9f %.9f %.9f\n", p.stamp, p.position.x(),
                 p.position.y(), p.position.z(), q.x(), q.y(), q.z(), q.w());
  }
  const bool ok = std::ferror(file) == 0;
  if (std::fclose(file) != 0 || !ok) throw DatasetError("cannot write trajectory '" + path + "'");
}

std::string toTumLine(const Pose4& pose) {
  const std::array<double, 4> q = yawQuaternion(pose.yaw);
  char line[256];
  std::snprintf(line, sizeof(line), "%.9f %.9g %.9g %.9g %.9g %.9g %.9g %.9g", pose.stamp, pose.x,
                pose.y, pose.z, q[0], q[1], q[2], q[3]);
  return line;
}

std::string toTumLine(const Pose4& pose, const CameraTilt& tilt) {
  const Eigen::Quaterniond q = cameraBodyOrientation(pose.yaw, tilt);
  char line[256];
  std::snprintf(line, sizeof(line), "%.9f %.9g %.9g %.9g %.9g %.9g %.9g %.9g", pose.stamp, pose.x, pose.y, pose.z,
                q.x(), q.y(), q.z(), q.w());
  return line;
}

}  // namespace oefmt
