// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/estimation/plane_tilt_tracker.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include "oefmt/registration/plane_tilt.h"
#include "oefmt/registration/robust_statistics.h"

namespace oefmt {
namespace {

// Tukey's biweight threshold in robust sigmas (95 % efficiency on Gaussian readings): readings
// far from the median (parallax) count for nothing, and a reading's weight falls smoothly on the
// way there, so that a tiny change of one reading never flips the line.
constexpr double kTukey = 4.685;

// The value at the last index of a weighted least-squares line through `values` (index = arrival
// order), each reading weighted by Tukey's biweight of its distance from their median.
double lineEnd(const std::vector<double>& values) {
  const double centre = medianOf(values);
  std::vector<double> deviations;
  deviations.reserve(values.size());
  for (double v : values) deviations.push_back(std::fabs(v - centre));
  const double limit = kTukey * kMadToSigma * medianOf(deviations);
  // Index t counted back from the newest (t = 0), so the line's intercept is its end.
  double n = 0.0, st = 0.0, sv = 0.0, stt = 0.0, stv = 0.0;
  const double newest = static_cast<double>(values.size() - 1);
  for (std::size_t i = 0; i < values.size(); ++i) {
    const double u = limit > 0.0 ? (values[i] - centre) / limit : 0.0;
    if (!(u * u < 1.0)) continue;
    const double w = (1.0 - u * u) * (1.0 - u * u);
    const double t = static_cast<double>(i) - newest;
    n += w;
    st += w * t;
    sv += w * values[i];
    stt += w * t * t;
    stv += w * t * values[i];
  }
  const double det = n * stt - st * st;
  if (!(det > 0.0)) return centre;
  return (stt * sv - st * stv) / det;
}

}  // namespace

void PlaneTiltTracker::add(double stretch_a, double stretch_b, const cv::Point2d& translation) {
  if (!(std::hypot(translation.x, translation.y) > 0.0)) return;
  const cv::Point2d reading = tiltFromStretch(stretch_a, stretch_b, translation);
  if (!std::isfinite(reading.x) || !std::isfinite(reading.y)) return;
  readings_.push_back(reading);
  if (readings_.size() > kReadings) readings_.pop_front();
}

void PlaneTiltTracker::turn(double rotation) {
  if (!std::isfinite(rotation)) return;
  // Image vectors of the older frame appear in the newer one turned by R = [cos sin; -sin cos].
  const double c = std::cos(rotation), s = std::sin(rotation);
  for (cv::Point2d& v : readings_) v = {c * v.x + s * v.y, -s * v.x + c * v.y};
}

cv::Point2d PlaneTiltTracker::tilt() const {
  if (readings_.size() < kMinimumReadings) return {};
  std::vector<double> xs, ys;
  xs.reserve(readings_.size());
  ys.reserve(readings_.size());
  for (const cv::Point2d& v : readings_) {
    xs.push_back(v.x);
    ys.push_back(v.y);
  }
  return {lineEnd(xs), lineEnd(ys)};
}

}  // namespace oefmt
