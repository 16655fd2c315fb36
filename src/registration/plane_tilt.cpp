// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/registration/plane_tilt.h"

#include <cmath>

namespace oefmt {

cv::Point2d tiltFromStretch(double stretch_a, double stretch_b, const cv::Point2d& translation) {
  const double length = std::hypot(translation.x, translation.y);
  if (!(length > 0.0)) return {};
  const double ux = translation.x / length, uy = translation.y / length;
  // The stretch along the motion and across it: -|d| tilt_along / 2 and -|d| tilt_across / 2.
  const double along = stretch_a * (ux * ux - uy * uy) + 2.0 * stretch_b * ux * uy;
  const double across = -2.0 * stretch_a * ux * uy + stretch_b * (ux * ux - uy * uy);
  const double k = -2.0 / length;
  return {k * (along * ux - across * uy), k * (along * uy + across * ux)};
}

double logZoomOfTilt(const cv::Point2d& tilt, const cv::Point2d& translation) {
  return 1.5 * tilt.dot(translation);
}

}  // namespace oefmt
