// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/estimation/range_gate.h"

#include <algorithm>
#include <cmath>
#include <vector>

namespace oefmt {

RangeGate::RangeGate(double gate, int relock_after) : gate_(gate), relock_after_(std::max(1, relock_after)) {}

std::optional<double> RangeGate::measure(double vertical, double predicted, const std::vector<double>& depth_ratios) {
  if (!std::isfinite(vertical) || !(vertical > 0.0) || !std::isfinite(predicted) || !(predicted > 0.0)) {
    return std::nullopt;
  }
  const double ratio = vertical / predicted;
  // The layer whose depth ratio the reading fits best: the reference plane's own (1) or another's.
  double best = 1.0;
  for (const double c : depth_ratios) {
    if (c > 0.0 && std::fabs(ratio / c - 1.0) < std::fabs(ratio / best - 1.0)) best = c;
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

bool RangeAltitude::update(Estimator& estimator, const Estimate& estimate, std::optional<double> vertical) {
  if (!vertical || estimate.state != TrackingState::kTracking) return false;
  const RangeObservation observation = rangeObservation(estimator, estimate, *vertical);
  const std::optional<double> altitude =
      gate_.measure(observation.vertical, observation.predicted, observation.depth_ratios);
  if (!altitude) return false;
  const double unseen = std::hypot(estimate.pose.x - last_x_, estimate.pose.y - last_y_) * attitude_sigma_;
  estimator.observeAltitude(*altitude, reading_sigma_, unseen * unseen);
  last_x_ = estimator.pose().x;
  last_y_ = estimator.pose().y;
  return true;
}

RangeObservation rangeObservation(const Estimator& estimator, const Estimate& estimate, double vertical) {
  return {vertical, estimator.altitude(),
          depthRatios(estimate.registration12.translation_energy, estimator.shiftPerBin(), estimate.step.shift())};
}

std::optional<double> rangeScale(const std::vector<RangeObservation>& observations, double gate, int min_support) {
  const auto fits = [gate](const RangeObservation& o, double factor) {
    const double ratio = o.vertical / (factor * o.predicted);
    if (std::fabs(ratio - 1.0) <= gate) return true;
    return std::any_of(o.depth_ratios.begin(), o.depth_ratios.end(),
                       [&](double c) { return c > 0.0 && std::fabs(ratio / c - 1.0) <= gate; });
  };
  std::optional<double> best;
  int best_support = 0;
  for (const RangeObservation& proposer : observations) {
    if (!(proposer.vertical > 0.0) || !(proposer.predicted > 0.0)) continue;
    std::vector<double> layers{1.0};
    layers.insert(layers.end(), proposer.depth_ratios.begin(), proposer.depth_ratios.end());
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
