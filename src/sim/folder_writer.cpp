// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/sim/folder_writer.h"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "oefmt/io/image_encoding.h"

namespace oefmt {
namespace sim {
namespace fs = std::filesystem;

StampedPose toStampedPose(const FlightPose& pose, double stamp) {
  StampedPose out;
  out.stamp = stamp;
  out.position = Eigen::Vector3d(pose.position[0], pose.position[1], pose.position[2]);
  out.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(pose.yaw, Eigen::Vector3d::UnitZ()));
  if (!pose.level()) {
    out.orientation = out.orientation * Eigen::AngleAxisd(pose.pitch, Eigen::Vector3d::UnitY()) *
                      Eigen::AngleAxisd(pose.roll, Eigen::Vector3d::UnitX());
  }
  return out;
}

FolderFlightWriter::FolderFlightWriter(const std::string& directory, const CameraParameters& camera,
                                       int frame_count, std::vector<std::string> ground_truth_header)
    : directory_(directory), camera_(camera), header_(std::move(ground_truth_header)) {
  digits_ = std::max(4, static_cast<int>(std::to_string(std::max(1, frame_count)).size()));
  std::error_code error;
  fs::create_directories(fs::path(directory_) / "Images", error);
  if (error) throw DatasetError("cannot create '" + directory_ + "/Images': " + error.message());
}

void FolderFlightWriter::write(const cv::Mat& image, const FlightPose& pose, double stamp) {
  char name[32];
  std::snprintf(name, sizeof(name), "%0*d.png", digits_, static_cast<int>(names_.size()) + 1);
  const std::string path = (fs::path(directory_) / "Images" / name).string();
  try {
    writeImageFile(path, image);
  } catch (const std::exception& e) {
    throw DatasetError("cannot write image '" + path + "': " + e.what());
  }
  names_.push_back(name);
  truth_.push_back(toStampedPose(pose, stamp));
}

void FolderFlightWriter::finish() {
  const fs::path root(directory_);
  std::ofstream list(root / "imageList.txt");
  for (const std::string& name : names_) list << name << "\n";
  std::ofstream stamps(root / "timestamps.txt");
  char text[64];
  for (const StampedPose& pose : truth_) {
    std::snprintf(text, sizeof(text), "%.6f\n", pose.stamp);
    stamps << text;
  }
  if (!list || !stamps) throw DatasetError("cannot write imageList.txt or timestamps.txt in '" + directory_ + "'");
  writeCameraParameters((root / "cam_param.yaml").string(), camera_);
  writeTum((root / "groundtruth.tum").string(), truth_, header_);
}

}  // namespace sim
}  // namespace oefmt
