// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/estimation/range_gate.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "oefmt/registration/warp.h"

namespace oefmt {

RangeGate::RangeGate(double gate, int relock_after) : gate_(gate), relock_after_(std::max(1, relock_after)) {}

std::optional<double> RangeGate::measure(double vertical, double predicted, const std::vector<double>& depth_ratios,
                                         double centre_ratio) {
  if (!std::isfinite(vertical) || !(vertical > 0.0) || !std::isfinite(predicted) || !(predicted > 0.0)) {
    return std::nullopt;
  }
  const double ratio = vertical / predicted;
  // The layer whose depth ratio the reading fits best: the reference plane's own (1) or another's;
  // the one below the camera where that is known.
  double best = 1.0;
  if (centre_ratio > 0.0 && std::isfinite(centre_ratio)) {
    best = centre_ratio;
  } else {
    for (const double c : depth_ratios) {
      if (c > 0.0 && std::fabs(ratio / c - 1.0) < std::fabs(ratio / best - 1.0)) best = c;
    }
  }
  if (std::fabs(ratio / best - 1.0) <= gate_) {
    recent_ratios_.clear();
    ++accepted_;
    return vertical / best;
  }
  recent_ratios_.push_back(ratio);
  if (static_cast<int>(recent_ratios_.size()) > relock_after_) recent_ratios_.pop_front();
  if (static_cast<int>(recent_ratios_.size()) == relock_after_) {
    std::vector<double> sorted(recent_ratios_.begin(), recent_ratios_.end());
    std::nth_element(sorted.begin(), sorted.begin() + sorted.size() / 2, sorted.end());
    const double median = sorted[sorted.size() / 2];
    const bool consistent = std::all_of(recent_ratios_.begin(), recent_ratios_.end(),
                                        [&](double r) { return std::fabs(r / median - 1.0) <= gate_; });
    if (consistent && std::fabs(ratio / median - 1.0) <= gate_) {
      recent_ratios_.clear();
      ++accepted_;
      return vertical;
    }
  }
  ++refused_;
  return std::nullopt;
}

RangeAltitude::RangeAltitude(double reading_sigma, double attitude_sigma)
    : reading_sigma_(reading_sigma), attitude_sigma_(attitude_sigma) {}

bool RangeAltitude::update(Estimator& estimator, const Estimate& estimate, std::optional<double> vertical,
                           cv::Point2d beam) {
  if (!vertical || estimate.state != TrackingState::kTracking) return false;
  const RangeObservation observation = rangeObservation(estimator, estimate, *vertical, beam);
  const std::optional<double> altitude = gate_.measure(observation.vertical, observation.predicted,
                                                      observation.depth_ratios, observation.centre_ratio);
  if (!altitude) return false;
  const double unseen = std::hypot(estimate.pose.x - last_x_, estimate.pose.y - last_y_) * attitude_sigma_;
  estimator.observeAltitude(*altitude, reading_sigma_, unseen * unseen);
  last_x_ = estimator.pose().x;
  last_y_ = estimator.pose().y;
  return true;
}

cv::Point2d beamInFrame(const std::optional<CameraTilt>& tilt, double fx) {
  if (!tilt) return {0.0, 0.0};
  const Eigen::Vector2d at = opticalAxisInNadirView(*tilt, fx);
  return {at.x(), at.y()};
}

RangeObservation rangeObservation(const Estimator& estimator, const Estimate& estimate, double vertical,
                                  cv::Point2d beam) {
  RangeObservation observation;
  observation.vertical = vertical;
  observation.predicted = estimator.altitude();
  observation.depth_ratios =
      depthRatios(estimate.registration12.translation_energy, estimator.shiftPerBin(), estimate.step.shift());
  if (estimate.state == TrackingState::kTracking) {
    observation.centre_ratio = estimator.centreDepthRatio(beam).value_or(0.0);
  }
  return observation;
}

std::optional<double> centreDepthRatio(const cv::Mat1f& older, const cv::Mat1f& newer, const PairMotion& motion,
                                       cv::Point2d beam) {
  const int n = newer.rows;
  if (older.empty() || older.size() != newer.size() || newer.cols != n || !motion.finite()) return std::nullopt;
  const int patch = (n / 4) & ~1;
  const double length = motion.shift();
  if (patch < 16 || !(length >= 1.0)) return std::nullopt;
  // The newer frame's centre patch (where the rangefinder reads), and the older frame's content
  // that would appear there if it moved with the followed layer (whole pixels).
  const cv::Point shift(static_cast<int>(std::lround(motion.translation.x)),
                        static_cast<int>(std::lround(motion.translation.y)));
  const double c = imageCentre(n);
  if (!std::isfinite(beam.x) || !std::isfinite(beam.y)) return std::nullopt;
  const cv::Rect newer_rect(static_cast<int>(std::lround(c + beam.x)) - patch / 2,
                            static_cast<int>(std::lround(c + beam.y)) - patch / 2, patch, patch);
  if ((newer_rect & cv::Rect(0, 0, n, n)) != newer_rect) return std::nullopt;
  // The inverse of B(c + M (p - c) + d) = A(p), M = s R(theta) (PairRegistration's convention).
  const double s = std::exp(motion.log_zoom);
  const double cs = std::cos(motion.rotation), sn = std::sin(motion.rotation);
  const cv::Matx22d inverse(cs / s, -sn / s, sn / s, cs / s);
  const cv::Vec2d origin = cv::Vec2d(c, c) + inverse * cv::Vec2d(newer_rect.x - c - shift.x, newer_rect.y - c - shift.y);
  for (const cv::Vec2d& corner : {cv::Vec2d(0, 0), cv::Vec2d(patch, 0), cv::Vec2d(0, patch), cv::Vec2d(patch, patch)}) {
    const cv::Vec2d p = origin + inverse * corner;
    if (!(p[0] >= 0.0 && p[1] >= 0.0 && p[0] <= n - 1 && p[1] <= n - 1)) return std::nullopt;
  }
  const cv::Matx23d map(inverse(0, 0), inverse(0, 1), origin[0], inverse(1, 0), inverse(1, 1), origin[1]);
  cv::Mat1f older_patch;
  cv::warpAffine(older, older_patch, map, cv::Size(patch, patch), cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                 cv::BORDER_REPLICATE);
  const cv::Mat1f newer_patch = newer(newer_rect).clone();
  // A patch without texture has no phase to correlate (its cross power is rounding noise).
  const auto textured = [](const cv::Mat1f& p) {
    cv::Scalar mean, deviation;
    cv::meanStdDev(p, mean, deviation);
    return deviation[0] > 1e-4 * (1.0 + std::fabs(mean[0]));
  };
  if (!textured(older_patch) || !textured(newer_patch)) return std::nullopt;
  cv::Mat1f window;
  cv::createHanningWindow(window, older_patch.size(), CV_32F);
  double response = 0.0;
  const cv::Point2d residual = cv::phaseCorrelate(older_patch, newer_patch, window, &response);
  // Pure noise: about patch^2 independent values of standard deviation 1 / patch, whose largest
  // is sqrt(2 ln(patch^2)) / patch.
  const double noise_peak = std::sqrt(2.0 * std::log(double(patch) * patch)) / patch;
  if (!(response >= 3.0 * noise_peak)) return std::nullopt;
  // The centre's own shift, along the followed layer's direction.
  const cv::Point2d centre_shift = cv::Point2d(shift) + residual;
  const double along = centre_shift.dot(motion.translation) / length;
  if (!(along > 0.0)) return std::nullopt;
  return length / along;
}

std::optional<double> rangeScale(const std::vector<RangeObservation>& observations, double gate, int min_support) {
  const auto fits = [gate](const RangeObservation& o, double factor) {
    const double ratio = o.vertical / (factor * o.predicted);
    if (o.centre_ratio > 0.0) return std::fabs(ratio / o.centre_ratio - 1.0) <= gate;
    if (std::fabs(ratio - 1.0) <= gate) return true;
    return std::any_of(o.depth_ratios.begin(), o.depth_ratios.end(),
                       [&](double c) { return c > 0.0 && std::fabs(ratio / c - 1.0) <= gate; });
  };
  std::optional<double> best;
  int best_support = 0;
  for (const RangeObservation& proposer : observations) {
    if (!(proposer.vertical > 0.0) || !(proposer.predicted > 0.0)) continue;
    std::vector<double> layers{1.0};
    if (proposer.centre_ratio > 0.0) {
      layers = {proposer.centre_ratio};
    } else {
      layers.insert(layers.end(), proposer.depth_ratios.begin(), proposer.depth_ratios.end());
    }
    for (const double c : layers) {
      if (!(c > 0.0)) continue;
      const double factor = proposer.vertical / (c * proposer.predicted);
      const int support = static_cast<int>(
          std::count_if(observations.begin(), observations.end(), [&](const RangeObservation& o) { return fits(o, factor); }));
      // Ties (readings that all saw the same layers): the smaller factor, i.e. the readings saw
      // the farthest layer they could have, the ground, which is below the vehicle most often.
      if (support > best_support || (support == best_support && best && factor < *best)) {
        best = factor;
        best_support = support;
      }
    }
  }
  if (best_support < min_support) return std::nullopt;
  return best;
}

std::vector<double> depthRatios(const std::vector<float>& energy, double shift_per_bin, double followed_shift) {
  std::vector<double> ratios;
  if (energy.size() < 3 || !(shift_per_bin > 0.0) || !(followed_shift > 0.0)) return ratios;
  const float highest = *std::max_element(energy.begin(), energy.end());
  if (!(highest > 0.0f)) return ratios;
  for (std::size_t j = 1; j + 1 < energy.size(); ++j) {
    const float left = energy[j - 1], centre = energy[j], right = energy[j + 1];
    if (!(centre > left && centre >= right && centre >= 0.25f * highest)) continue;
    const double curvature = left - 2.0 * centre + right;
    const double offset = curvature < 0.0 ? 0.5 * (left - right) / curvature : 0.0;
    const double shift = (static_cast<double>(j) + offset) * shift_per_bin;
    if (shift > 0.0) ratios.push_back(followed_shift / shift);
  }
  return ratios;
}

}  // namespace oefmt
