// SPDX-License-Identifier: GPL-3.0-or-later
// Trajectory evaluation: association, similarity alignment (Umeyama), absolute
// trajectory error, drift per distance travelled and loop error.
#pragma once

#include <cmath>
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "oefmt/enum_names.h"
#include "oefmt/io/tum.h"

namespace oefmt {

/// Pairs (estimate index, ground-truth index).
using Association = std::vector<std::pair<std::size_t, std::size_t>>;

/// Matches each estimated pose with the ground-truth pose nearest in time, if within `tolerance`
/// seconds; each ground-truth pose is used at most once. Both trajectories must be time-ordered.
Association associateByTime(const StampedTrajectory& estimate, const StampedTrajectory& truth, double tolerance);

/// Matches pose k with pose k for k < min(sizes).
Association associateByIndex(const StampedTrajectory& estimate, const StampedTrajectory& truth);

/// x -> scale * rotation * x + translation.
struct Similarity {
  double scale = 1.0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d translation = Eigen::Vector3d::Zero();

  Eigen::Vector3d apply(const Eigen::Vector3d& p) const { return scale * (rotation * p) + translation; }
  /// The yaw of the rotation (about z) [rad].
  double yaw() const;
};

/// Least-squares alignment of `source` onto `target` (Umeyama). planar: rotation about z, scale
/// and x-y translation fitted to x-y only, z then shifted so the mean heights agree; otherwise a
/// full 3-D fit. with_scale false fixes scale at 1 (rigid). Throws InputError with fewer than 2
/// pairs, mismatched sizes, or source points that all coincide.
Similarity alignTrajectories(const std::vector<Eigen::Vector3d>& source,
                             const std::vector<Eigen::Vector3d>& target, bool planar, bool with_scale);

struct ErrorStatistics {
  std::size_t count = 0;
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double max = 0.0;
};
ErrorStatistics errorStatistics(std::vector<double> errors);

enum class AssociationMode { kTimestamp, kIndex };
/// oefmt_evaluate's --match words.
inline constexpr EnumName<AssociationMode> kAssociationModeNames[] = {
    {AssociationMode::kTimestamp, "time"}, {AssociationMode::kIndex, "index"}};

struct EvaluationOptions {
  AssociationMode association = AssociationMode::kTimestamp;
  double time_tolerance = 0.02;    ///< [s], timestamp association only
  bool planar = true;              ///< align and measure in x-y (false: 3-D)
  bool with_scale = true;          ///< similarity (true) or rigid (false) alignment
  /// Segment lengths for the drift, as fractions of the ground truth's path length.
  std::vector<double> drift_segment_fractions = {0.1, 0.2, 0.3, 0.4, 0.5};
  /// A heading step (yaw change between consecutive matched poses) whose error exceeds this
  /// counts as off [rad].
  double heading_step_threshold = 2.0 * M_PI / 180.0;
};

/// Errors of the yaw change between consecutive matched poses: the estimate's change minus the
/// truth's, wrapped to (-pi, pi]. Independent of the alignment.
struct HeadingStepErrors {
  std::size_t count = 0;       ///< steps measured
  double rmse = 0.0;           ///< [rad]
  double max = 0.0;            ///< largest |error| [rad]
  std::size_t over_threshold = 0;  ///< steps with |error| > heading_step_threshold
};

/// Relative error over segments of one length.
struct DriftSegment {
  double length = 0.0;         ///< [m] of ground-truth path
  std::size_t count = 0;       ///< segments measured
  double mean_percent = 0.0;   ///< mean |displacement error| / length * 100
};

struct EvaluationResult {
  std::size_t estimate_poses = 0;
  std::size_t truth_poses = 0;
  std::size_t matched = 0;
  Similarity alignment;                ///< estimate -> ground truth
  ErrorStatistics ate;                 ///< absolute trajectory error after alignment [m]
  std::vector<double> errors;          ///< per matched pose [m]
  double path_length = 0.0;            ///< ground truth, over the matched poses [m]
  std::vector<DriftSegment> drift;     ///< per segment length
  double drift_percent = 0.0;          ///< mean over all segments of all lengths [%]
  /// |(est_last - est_first) - (gt_last - gt_first)| after alignment [m]: for a closed loop, the
  /// gap the estimate leaves where the truth closes.
  double loop_error = 0.0;
  double loop_error_percent = 0.0;     ///< loop_error / path_length * 100
  HeadingStepErrors heading_steps;
  StampedTrajectory aligned_estimate;         ///< matched estimate poses after alignment
  StampedTrajectory matched_truth;            ///< their ground-truth poses
};

/// Associates, aligns and measures. Throws InputError when too few poses match.
EvaluationResult evaluateTrajectory(const StampedTrajectory& estimate, const StampedTrajectory& truth,
                                    const EvaluationOptions& options);

/// One line of JSON with every figure of the result (no per-pose data).
std::string evaluationJson(const EvaluationResult& result, const EvaluationOptions& options);

/// A human-readable table of the result.
std::string evaluationTable(const EvaluationResult& result, const EvaluationOptions& options);

}  // namespace oefmt
