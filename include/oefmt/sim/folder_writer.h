// SPDX-License-Identifier: GPL-3.0-or-later
// Writes a flight in the authors' dataset layout (read back by oefmt::FolderDataset):
// Images/0001.png..., imageList.txt, timestamps.txt (seconds), cam_param.yaml, groundtruth.tum.
#pragma once

#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/io/dataset.h"
#include "oefmt/io/tum.h"
#include "oefmt/sim/camera_model.h"

namespace oefmt {
namespace sim {

/// The TUM pose of a flight pose (orientation: yaw about z).
StampedPose toStampedPose(const FlightPose& pose, double stamp);

class FolderFlightWriter {
 public:
  /// Creates `directory` and its Images/ folder (existing files of the same names are replaced).
  /// Images are named with at least 4 digits, from 1. Throws DatasetError when it cannot.
  FolderFlightWriter(const std::string& directory, const CameraParameters& camera, int frame_count,
                     std::vector<std::string> ground_truth_header);

  /// Writes the next image (PNG) and records its pose and stamp. Throws DatasetError.
  void write(const cv::Mat& image, const FlightPose& pose, double stamp);

  /// Writes imageList.txt, timestamps.txt, cam_param.yaml and groundtruth.tum.
  void finish();

  const std::string& directory() const { return directory_; }

 private:
  std::string directory_;
  CameraParameters camera_;
  int digits_;
  std::vector<std::string> header_;
  std::vector<std::string> names_;
  StampedTrajectory truth_;
};

}  // namespace sim
}  // namespace oefmt
