// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/estimation/pair_motion.h"

#include <algorithm>

namespace oefmt {

double wrapToPi(double angle) {
  if (!std::isfinite(angle)) return angle;
  double a = std::fmod(angle + CV_PI, 2.0 * CV_PI);
  if (a <= 0.0) a += 2.0 * CV_PI;
  return a - CV_PI;
}

cv::Matx22d alongAcrossCovariance(double angle, double along, double across) {
  const double c = std::cos(angle), s = std::sin(angle);
  const double a2 = along * along, b2 = across * across;
  return {c * c * a2 + s * s * b2, c * s * (a2 - b2),
          c * s * (a2 - b2), s * s * a2 + c * c * b2};
}

bool PairMotion::finite() const {
  const cv::Matx22d& p = translation_covariance;
  return std::isfinite(rotation) && std::isfinite(log_zoom) && std::isfinite(translation.x) &&
         std::isfinite(translation.y) && std::isfinite(rotation_sigma) && rotation_sigma >= 0.0 &&
         std::isfinite(log_zoom_sigma) && log_zoom_sigma >= 0.0 && std::isfinite(p(0, 0)) &&
         std::isfinite(p(0, 1)) && std::isfinite(p(1, 0)) && std::isfinite(p(1, 1)) &&
         p(0, 0) >= 0.0 && p(1, 1) >= 0.0;
}

PairMotion PairMotion::fromRegistration(const PairRegistration& r) {
  PairMotion m;
  m.rotation = wrapToPi(r.rotation);
  m.log_zoom = r.zoom > 0.0 ? std::log(r.zoom) : 0.0;
  m.translation = r.translation;
  m.rotation_sigma = r.rotation_sigma;
  m.log_zoom_sigma = r.log_zoom_sigma;
  const double shift = std::hypot(r.translation.x, r.translation.y);
  // Below a pixel the direction is meaningless: the shift's sigma holds in every direction.
  const double across =
      shift >= 1.0 ? std::max(shift * r.direction_sigma, 0.02) : r.shift_sigma;
  m.translation_covariance =
      alongAcrossCovariance(std::atan2(r.translation.y, r.translation.x), r.shift_sigma,
                            std::max(across, 0.0));
  return m;
}

}  // namespace oefmt
