// SPDX-License-Identifier: GPL-3.0-or-later
// The ground plane's tilt in a levelled view (the attitude source's error), from the stretch of
// the last pairs, for Registrar::setPlaneTilt.
#pragma once

#include <deque>

#include <opencv2/core/types.hpp>

namespace oefmt {

class PlaneTiltTracker {
 public:
  /// Readings kept: an attitude filter's error wanders over seconds, one pair's stretch is noisy,
  /// and parallax makes some of them outliers.
  static constexpr std::size_t kReadings = 30;
  /// Readings before there is an estimate.
  static constexpr std::size_t kMinimumReadings = 10;

  /// A pair whose refinement measured its stretch, in the newer frame's image axes.
  void add(double stretch_a, double stretch_b, const cv::Point2d& translation);
  /// The newest frame turned by `rotation` against the one before (PairRegistration's
  /// convention): the readings follow it into its axes.
  void turn(double rotation);
  void clear() { readings_.clear(); }
  std::size_t readings() const { return readings_.size(); }

  /// The tilt [1/px, the newest frame's image axes] at the newest reading: per axis a straight
  /// line fitted to the readings in the order they came, each weighted by Tukey's biweight of its
  /// distance from their median (4.685 robust sigmas: the weights fall smoothly, so that a tiny
  /// change of one reading moves the line a little and never flips it). A median of the window
  /// would lag half of it behind a tilt that wanders (on the tilting flights of the benchmarks
  /// the estimate then correlated best with the truth of 15 frames before); the line's end does
  /// not. Zero before kMinimumReadings.
  cv::Point2d tilt() const;

 private:
  std::deque<cv::Point2d> readings_;
};

}  // namespace oefmt
