// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/registration/plane_tilt.h"

#include <cmath>

namespace oefmt {

cv::Point2d tiltFromStretch(double stretch_a, double stretch_b, const cv::Point2d& translation) {
  const double length = std::hypot(translation.x, translation.y);
  if (!(length > 0.0)) return {};
  const double ux = translation.x / length, uy = translation.y / length;
  // S u holds the stretch along the motion u (u^T S u = -|d| tilt.u / 2) and across it, alike:
  // S u = -|d| tilt / 2.
  const double k = -2.0 / length;
  return {k * (stretch_a * ux + stretch_b * uy), k * (stretch_b * ux - stretch_a * uy)};
}

double logZoomOfTilt(const cv::Point2d& tilt, const cv::Point2d& translation) {
  return 1.5 * tilt.dot(translation);
}

double rotationOfTilt(const cv::Point2d& tilt, const cv::Point2d& translation) {
  return 0.5 * (translation.x * tilt.y - translation.y * tilt.x);
}

double rotationOfSlope(double stretch_a, double stretch_b, const cv::Point2d& translation) {
  return rotationOfTilt(tiltFromStretch(stretch_a, stretch_b, translation), translation);
}

double logZoomOfSlope(double stretch_a, double stretch_b, const cv::Point2d& translation) {
  return 0.5 * tiltFromStretch(stretch_a, stretch_b, translation).dot(translation);
}

}  // namespace oefmt
