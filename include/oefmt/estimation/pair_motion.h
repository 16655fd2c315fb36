// SPDX-License-Identifier: GPL-3.0-or-later
// The motion of one frame pair with its uncertainty: what the local optimizer refines and the
// pose integrator accumulates.
#pragma once

#include <cmath>

#include <opencv2/core.hpp>

#include "oefmt/registration/registration.h"

namespace oefmt {

/// Motion of an older frame A to a newer frame B, in the conventions of PairRegistration:
/// x_B - c = s R(theta) (x_A - c) + d, c = imageCentre(N) (the principal point), image axes
/// (x right, y down), theta > 0 turns B's content counter-clockwise on screen, d in B's pixels. The camera itself moved by -R(theta) d / s in
/// A's pixels, where R(a) adds a to image angles atan2(dy, dx).
struct PairMotion {
  double rotation = 0.0;   ///< theta [rad], in (-pi, pi]
  double log_zoom = 0.0;   ///< ln s (s > 1: B looks larger, the camera descended)
  cv::Point2d translation; ///< d [px of B]
  double rotation_sigma = 0.0;        ///< 1-sigma of theta [rad]
  double log_zoom_sigma = 0.0;        ///< 1-sigma of ln s
  cv::Matx22d translation_covariance; ///< covariance of d [px^2] (B's image axes)

  double zoom() const { return std::exp(log_zoom); }
  double shift() const { return std::hypot(translation.x, translation.y); }
  double direction() const { return std::atan2(translation.y, translation.x); }
  /// Every field finite and every variance >= 0.
  bool finite() const;

  /// From a registration: d's covariance is shift_sigma along d and shift * direction_sigma
  /// across it (shift_sigma in every direction when d is shorter than a pixel).
  static PairMotion fromRegistration(const PairRegistration& registration);
};

/// Covariance of a 2-D vector of length `length` along angle `angle`, with 1-sigma `along` in its
/// direction and `across` perpendicular to it [px^2].
cv::Matx22d alongAcrossCovariance(double angle, double along, double across);

/// Rotates image vector v by angle a (adds a to atan2(v.y, v.x)).
inline cv::Point2d rotateImageVector(const cv::Point2d& v, double a) {
  const double c = std::cos(a), s = std::sin(a);
  return {c * v.x - s * v.y, s * v.x + c * v.y};
}

/// Angle wrapped to (-pi, pi].
double wrapToPi(double angle);

}  // namespace oefmt
