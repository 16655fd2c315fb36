// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/sim/camera_model.h"

#include <algorithm>
#include <cmath>


#include "oefmt/error.h"

namespace oefmt {
namespace sim {
namespace {

double signedArea(const std::vector<cv::Point2d>& polygon) {
  double twice = 0.0;
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const cv::Point2d& a = polygon[i];
    const cv::Point2d& b = polygon[(i + 1) % polygon.size()];
    twice += a.x * b.y - b.x * a.y;
  }
  return 0.5 * twice;
}

// Area of subject clipped by a convex polygon (Sutherland-Hodgman). Unlike
// cv::intersectConvexConvex it is exact when edges are collinear (frames moving along an axis).
double intersectionArea(std::vector<cv::Point2d> subject, const std::vector<cv::Point2d>& convex) {
  const double orientation = signedArea(convex) >= 0.0 ? 1.0 : -1.0;
  for (std::size_t e = 0; e < convex.size() && !subject.empty(); ++e) {
    const cv::Point2d a = convex[e], b = convex[(e + 1) % convex.size()];
    const auto side = [&](const cv::Point2d& p) { return orientation * ((b - a).cross(p - a)); };
    std::vector<cv::Point2d> clipped;
    for (std::size_t i = 0; i < subject.size(); ++i) {
      const cv::Point2d p = subject[i], q = subject[(i + 1) % subject.size()];
      const double sp = side(p), sq = side(q);
      if (sp >= 0.0) clipped.push_back(p);
      if ((sp >= 0.0) != (sq >= 0.0)) clipped.push_back(p + (q - p) * (sp / (sp - sq)));
    }
    subject = std::move(clipped);
  }
  return subject.size() >= 3 ? std::fabs(signedArea(subject)) : 0.0;
}

std::vector<cv::Point2d> toDouble(const std::vector<cv::Point2f>& points) {
  return std::vector<cv::Point2d>(points.begin(), points.end());
}

// OpenCV's radial factor: (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6).
double radialFactor(const Distortion& d, double r2) {
  // Spelled term by term, as before k3..k6 existed, so plumb_bob renders stay bit-identical.
  const double numerator = 1.0 + d.k1 * r2 + d.k2 * r2 * r2 + d.k3 * r2 * r2 * r2;
  const double denominator = 1.0 + d.k4 * r2 + d.k5 * r2 * r2 + d.k6 * r2 * r2 * r2;
  return numerator / denominator;
}

cv::Point2d tangentialTerm(const Distortion& d, cv::Point2d p) {
  const double r2 = p.x * p.x + p.y * p.y;
  return {2.0 * d.p1 * p.x * p.y + d.p2 * (r2 + 2.0 * p.x * p.x),
          d.p1 * (r2 + 2.0 * p.y * p.y) + 2.0 * d.p2 * p.x * p.y};
}

}  // namespace

cv::Matx33d opticalToWorld(double yaw) {
  const double c = std::cos(yaw), s = std::sin(yaw);
  // Rz(yaw) * diag(1, -1, -1).
  return cv::Matx33d(c, s, 0.0,
                     s, -c, 0.0,
                     0.0, 0.0, -1.0);
}

cv::Matx33d bodyToWorld(const FlightPose& pose) {
  const double cz = std::cos(pose.yaw), sz = std::sin(pose.yaw);
  const double cy = std::cos(pose.pitch), sy = std::sin(pose.pitch);
  const double cx = std::cos(pose.roll), sx = std::sin(pose.roll);
  const cv::Matx33d z(cz, -sz, 0.0, sz, cz, 0.0, 0.0, 0.0, 1.0);
  const cv::Matx33d y(cy, 0.0, sy, 0.0, 1.0, 0.0, -sy, 0.0, cy);
  const cv::Matx33d x(1.0, 0.0, 0.0, 0.0, cx, -sx, 0.0, sx, cx);
  return z * y * x;
}

cv::Matx33d opticalToWorld(const FlightPose& pose) {
  // A level pose's rotation exactly as before tilt existed: level flights render bit-identically.
  if (pose.level()) return opticalToWorld(pose.yaw);
  return bodyToWorld(pose) * cv::Matx33d(1.0, 0.0, 0.0, 0.0, -1.0, 0.0, 0.0, 0.0, -1.0);
}

cv::Point2d distortNormalised(const Distortion& d, cv::Point2d p) {
  return p * radialFactor(d, p.x * p.x + p.y * p.y) + tangentialTerm(d, p);
}

cv::Point2d undistortNormalised(const Distortion& d, cv::Point2d distorted) {
  if (!d.any()) return distorted;
  // p = (distorted - tangential(p)) / radial(p), iterated to its fixed point.
  cv::Point2d p = distorted;
  for (int iteration = 0; iteration < 200; ++iteration) {
    const cv::Point2d next = (distorted - tangentialTerm(d, p)) / radialFactor(d, p.x * p.x + p.y * p.y);
    const cv::Point2d step = next - p;
    p = next;
    if (step.dot(step) < 1e-28) break;
  }
  return p;
}

cv::Point2d pixelOnPlane(const CameraParameters& camera, const FlightPose& pose, cv::Point2d pixel,
                         double plane_height) {
  const Intrinsics& k = camera.intrinsics;
  const cv::Point2d n = undistortNormalised(
      camera.distortion, {(pixel.x - k.cx) / k.fx, (pixel.y - k.cy) / k.fy});
  const cv::Vec3d ray = opticalToWorld(pose) * cv::Vec3d(n.x, n.y, 1.0);
  const double depth = pose.position[2] - plane_height;
  if (!(depth > 0.0)) throw InputError("the camera must be above the plane z = " + std::to_string(plane_height));
  if (!(ray[2] < 0.0)) throw InputError("a pixel's ray does not meet the plane: the camera is tilted too far");
  const double t = depth / -ray[2];
  return {pose.position[0] + t * ray[0], pose.position[1] + t * ray[1]};
}

std::vector<cv::Point2f> groundFootprint(const CameraParameters& camera, const FlightPose& pose,
                                         double plane_height) {
  const double right = camera.intrinsics.width - 0.5, bottom = camera.intrinsics.height - 0.5;
  std::vector<cv::Point2f> outline;
  for (const cv::Point2d corner : {cv::Point2d(-0.5, -0.5), cv::Point2d(right, -0.5),
                                   cv::Point2d(right, bottom), cv::Point2d(-0.5, bottom)}) {
    outline.push_back(cv::Point2f(pixelOnPlane(camera, pose, corner, plane_height)));
  }
  return outline;
}

double footprintOverlap(const CameraParameters& camera, const FlightPose& a, const FlightPose& b,
                        double plane_height) {
  const std::vector<cv::Point2d> fa = toDouble(groundFootprint(camera, a, plane_height));
  const std::vector<cv::Point2d> fb = toDouble(groundFootprint(camera, b, plane_height));
  const double area_a = std::fabs(signedArea(fa));
  return area_a > 0.0 ? intersectionArea(fa, fb) / area_a : 0.0;
}

OverlapStatistics consecutiveOverlap(const CameraParameters& camera, const std::vector<FlightPose>& poses,
                                     double plane_height) {
  OverlapStatistics stats;
  if (poses.size() < 2) return stats;
  stats.min = 1.0;
  double sum = 0.0;
  for (std::size_t k = 1; k < poses.size(); ++k) {
    const double overlap = footprintOverlap(camera, poses[k - 1], poses[k], plane_height);
    stats.min = std::min(stats.min, overlap);
    stats.max = std::max(stats.max, overlap);
    sum += overlap;
  }
  stats.mean = sum / static_cast<double>(poses.size() - 1);
  return stats;
}

}  // namespace sim
}  // namespace oefmt
