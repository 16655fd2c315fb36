// SPDX-License-Identifier: GPL-3.0-or-later
// The simulated down-looking camera: poses, the camera's orientation in the world, distortion.
//
// World frame (REP-103): x east, y north, z up. A pose is the body (base_link) pose: position and
// attitude (yaw, pitch, roll about z, y', x''). The camera is rigidly mounted looking down the
// body's -z axis; its optical frame (x right, y down, z forward) is the body frame turned 180
// degrees about x, so level and at yaw 0 image right = +x and image up = +y.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/io/dataset.h"

namespace oefmt {
namespace sim {

/// Pose of the camera body: position [m], yaw [rad] (counter-clockwise seen from above), and the
/// tilt of a vehicle without gimbal: pitch about the body's y axis, roll about its x axis [rad]
/// (zero: level).
struct FlightPose {
  cv::Vec3d position;
  double yaw = 0.0;
  double pitch = 0.0;
  double roll = 0.0;

  bool level() const { return pitch == 0.0 && roll == 0.0; }
};

/// Rotation of the body into the world: Rz(yaw) * Ry(pitch) * Rx(roll).
cv::Matx33d bodyToWorld(const FlightPose& pose);

/// Rotation of the camera's optical frame into the world: Rz(yaw) * Rx(pi) for a level pose,
/// bodyToWorld(pose) * Rx(pi) in general.
cv::Matx33d opticalToWorld(double yaw);
cv::Matx33d opticalToWorld(const FlightPose& pose);

/// Applies the radial-tangential (and rational) model to normalised coordinates (undistorted ->
/// distorted), as OpenCV does.
cv::Point2d distortNormalised(const Distortion& distortion, cv::Point2d undistorted);

/// Inverts distortNormalised by fixed-point iteration (accurate to ~1e-12 for usual lenses).
cv::Point2d undistortNormalised(const Distortion& distortion, cv::Point2d distorted);

/// Where the ray through pixel (u, v) (pixel centres at integer coordinates) meets the plane
/// z = plane_height, in world x-y. The camera must be above the plane.
cv::Point2d pixelOnPlane(const CameraParameters& camera, const FlightPose& pose, cv::Point2d pixel,
                         double plane_height);

/// The image's outline (its four corners) on the plane z = plane_height, world x-y.
std::vector<cv::Point2f> groundFootprint(const CameraParameters& camera, const FlightPose& pose,
                                         double plane_height);

/// Area fraction of the footprint of `a` on the plane that the footprint of `b` also covers.
double footprintOverlap(const CameraParameters& camera, const FlightPose& a, const FlightPose& b,
                        double plane_height);

struct OverlapStatistics {
  double min = 0.0;
  double mean = 0.0;
  double max = 0.0;
};
/// Overlap of each consecutive pair of poses on the plane z = plane_height.
OverlapStatistics consecutiveOverlap(const CameraParameters& camera, const std::vector<FlightPose>& poses,
                                     double plane_height);

}  // namespace sim
}  // namespace oefmt
