// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/evaluation/evaluation.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "oefmt/io/dataset.h"
#include "oefmt/error.h"

namespace oefmt {
namespace {

std::string format(const char* pattern, double value) {
  char text[64];
  std::snprintf(text, sizeof(text), pattern, value);
  return text;
}

// JSON has no NaN or infinity: undefined figures are null.
std::string jsonNumber(double value) { return std::isfinite(value) ? format("%.6g", value) : "null"; }

// The part of a position the errors are measured in.
Eigen::Vector3d measured(const Eigen::Vector3d& p, bool planar) {
  return planar ? Eigen::Vector3d(p.x(), p.y(), 0.0) : p;
}

std::vector<DriftSegment> measureDrift(const std::vector<Eigen::Vector3d>& estimate,
                                       const std::vector<Eigen::Vector3d>& truth,
                                       const std::vector<double>& travelled, double path_length,
                                       const std::vector<double>& fractions) {
  std::vector<DriftSegment> segments;
  const std::size_t n = truth.size();
  for (double fraction : fractions) {
    DriftSegment segment;
    segment.length = fraction * path_length;
    if (!(segment.length > 0.0)) continue;
    double sum = 0.0;
    std::size_t j = 0;
    for (std::size_t i = 0; i < n; ++i) {
      j = std::max(j, i + 1);
      while (j < n && travelled[j] - travelled[i] < segment.length) ++j;
      if (j >= n) break;
      const double distance = travelled[j] - travelled[i];
      const Eigen::Vector3d error = (estimate[j] - estimate[i]) - (truth[j] - truth[i]);
      sum += error.norm() / distance * 100.0;
      ++segment.count;
    }
    if (segment.count > 0) segment.mean_percent = sum / static_cast<double>(segment.count);
    segments.push_back(segment);
  }
  return segments;
}

// Yaw about z of an orientation (body to world) [rad].
double yawOf(const Eigen::Quaterniond& q) {
  return std::atan2(2.0 * (q.w() * q.z() + q.x() * q.y()), 1.0 - 2.0 * (q.y() * q.y() + q.z() * q.z()));
}

double wrapAngle(double a) { return std::remainder(a, 2.0 * M_PI); }

HeadingStepErrors measureHeadingSteps(const StampedTrajectory& estimate, const StampedTrajectory& truth,
                                      double threshold) {
  HeadingStepErrors steps;
  double squares = 0.0;
  for (std::size_t k = 1; k < estimate.size(); ++k) {
    const double estimated = yawOf(estimate[k].orientation) - yawOf(estimate[k - 1].orientation);
    const double true_change = yawOf(truth[k].orientation) - yawOf(truth[k - 1].orientation);
    const double error = std::fabs(wrapAngle(estimated - true_change));
    ++steps.count;
    squares += error * error;
    steps.max = std::max(steps.max, error);
    if (error > threshold) ++steps.over_threshold;
  }
  if (steps.count > 0) steps.rmse = std::sqrt(squares / steps.count);
  return steps;
}

}  // namespace

Association associateByTime(const StampedTrajectory& estimate, const StampedTrajectory& truth, double tolerance) {
  Association pairs;
  if (truth.empty()) return pairs;
  std::size_t j = 0;
  std::size_t last_used = truth.size();  // none yet
  for (std::size_t i = 0; i < estimate.size(); ++i) {
    const double t = estimate[i].stamp;
    while (j + 1 < truth.size() && truth[j + 1].stamp <= t) ++j;
    // Nearest of truth[j] and truth[j + 1].
    std::size_t best = j;
    if (j + 1 < truth.size() && std::fabs(truth[j + 1].stamp - t) < std::fabs(truth[j].stamp - t)) best = j + 1;
    if (std::fabs(truth[best].stamp - t) > tolerance || best == last_used) continue;
    pairs.emplace_back(i, best);
    last_used = best;
  }
  return pairs;
}

Association associateByIndex(const StampedTrajectory& estimate, const StampedTrajectory& truth) {
  Association pairs;
  for (std::size_t k = 0; k < std::min(estimate.size(), truth.size()); ++k) pairs.emplace_back(k, k);
  return pairs;
}

double Similarity::yaw() const { return std::atan2(rotation(1, 0), rotation(0, 0)); }

Similarity alignTrajectories(const std::vector<Eigen::Vector3d>& source,
                             const std::vector<Eigen::Vector3d>& target, bool planar, bool with_scale) {
  if (source.size() != target.size()) throw InputError("alignment: point sets differ in size");
  const int n = static_cast<int>(source.size());
  if (n < 2) throw InputError("alignment needs at least 2 matched poses, got " + std::to_string(n));
  const int dims = planar ? 2 : 3;
  Eigen::MatrixXd src(dims, n), dst(dims, n);
  for (int k = 0; k < n; ++k) {
    src.col(k) = source[k].head(dims);
    dst.col(k) = target[k].head(dims);
  }
  const double spread = (src.colwise() - src.rowwise().mean()).squaredNorm();
  if (!(spread > 1e-18) && !with_scale) {
    // Nothing to turn (a camera that never moved): the rigid fit is a shift of the means.
    Similarity s;
    s.translation.head(dims) = dst.rowwise().mean() - src.rowwise().mean();
    if (planar) {
      double source_z = 0.0, target_z = 0.0;
      for (int k = 0; k < n; ++k) {
        source_z += source[k].z();
        target_z += target[k].z();
      }
      s.translation.z() = (target_z - source_z) / n;
    }
    return s;
  }
  if (!(spread > 1e-18)) throw InputError("alignment: the estimated positions all coincide");
  const Eigen::MatrixXd transform = Eigen::umeyama(src, dst, with_scale);
  Similarity s;
  const Eigen::MatrixXd linear = transform.topLeftCorner(dims, dims);
  // Umeyama returns scale * rotation; the columns' norm is the scale.
  s.scale = linear.col(0).norm();
  s.rotation.topLeftCorner(dims, dims) = linear / s.scale;
  s.translation.head(dims) = transform.topRightCorner(dims, 1);
  if (planar) {
    double source_z = 0.0, target_z = 0.0;
    for (int k = 0; k < n; ++k) {
      source_z += source[k].z();
      target_z += target[k].z();
    }
    s.translation.z() = (target_z - s.scale * source_z) / n;
  }
  return s;
}

ErrorStatistics errorStatistics(std::vector<double> errors) {
  ErrorStatistics stats;
  stats.count = errors.size();
  if (errors.empty()) return stats;
  double sum = 0.0, squares = 0.0;
  for (double e : errors) {
    sum += e;
    squares += e * e;
    stats.max = std::max(stats.max, e);
  }
  stats.mean = sum / errors.size();
  stats.rmse = std::sqrt(squares / errors.size());
  const std::size_t middle = errors.size() / 2;
  std::nth_element(errors.begin(), errors.begin() + middle, errors.end());
  stats.median = errors[middle];
  if (errors.size() % 2 == 0) {
    stats.median = 0.5 * (stats.median + *std::max_element(errors.begin(), errors.begin() + middle));
  }
  return stats;
}

EvaluationResult evaluateTrajectory(const StampedTrajectory& estimate, const StampedTrajectory& truth,
                                    const EvaluationOptions& options) {
  EvaluationResult result;
  result.estimate_poses = estimate.size();
  result.truth_poses = truth.size();
  const Association pairs = options.association == AssociationMode::kIndex
                                ? associateByIndex(estimate, truth)
                                : associateByTime(estimate, truth, options.time_tolerance);
  result.matched = pairs.size();
  if (pairs.size() < 2) {
    throw InputError("only " + std::to_string(pairs.size()) + " of " + std::to_string(estimate.size()) +
                     " estimated poses match the ground truth (" +
                     (options.association == AssociationMode::kIndex
                          ? std::string("by index")
                          : "timestamps within " + format("%g", options.time_tolerance) + " s") +
                     "): at least 2 are needed");
  }
  std::vector<Eigen::Vector3d> source, target;
  for (const auto& [e, t] : pairs) {
    source.push_back(estimate[e].position);
    target.push_back(truth[t].position);
  }
  result.alignment = alignTrajectories(source, target, options.planar, options.with_scale);
  const Eigen::Quaterniond turn(result.alignment.rotation);

  std::vector<Eigen::Vector3d> aligned(pairs.size()), reference(pairs.size());
  std::vector<double> travelled(pairs.size(), 0.0);
  for (std::size_t k = 0; k < pairs.size(); ++k) {
    StampedPose pose = estimate[pairs[k].first];
    pose.position = result.alignment.apply(pose.position);
    pose.orientation = (turn * pose.orientation).normalized();
    result.aligned_estimate.push_back(pose);
    result.matched_truth.push_back(truth[pairs[k].second]);
    aligned[k] = measured(pose.position, options.planar);
    reference[k] = measured(truth[pairs[k].second].position, options.planar);
    result.errors.push_back((aligned[k] - reference[k]).norm());
    if (k > 0) travelled[k] = travelled[k - 1] + (reference[k] - reference[k - 1]).norm();
  }
  result.ate = errorStatistics(result.errors);
  result.path_length = travelled.back();
  result.drift = measureDrift(aligned, reference, travelled, result.path_length,
                              options.drift_segment_fractions);
  double drift_sum = 0.0;
  std::size_t drift_count = 0;
  for (const DriftSegment& s : result.drift) {
    drift_sum += s.mean_percent * s.count;
    drift_count += s.count;
  }
  result.drift_percent = drift_count > 0 ? drift_sum / drift_count : std::nan("");
  result.loop_error = ((aligned.back() - aligned.front()) - (reference.back() - reference.front())).norm();
  result.loop_error_percent =
      result.path_length > 0.0 ? result.loop_error / result.path_length * 100.0 : std::nan("");
  result.heading_steps = measureHeadingSteps(result.aligned_estimate, result.matched_truth,
                                             options.heading_step_threshold);
  return result;
}

std::string evaluationJson(const EvaluationResult& r, const EvaluationOptions& options) {
  std::ostringstream json;
  json << "{\"estimate_poses\":" << r.estimate_poses << ",\"truth_poses\":" << r.truth_poses
       << ",\"matched\":" << r.matched << ",\"association\":\""
       << (options.association == AssociationMode::kIndex ? "index" : "timestamp") << "\""
       << ",\"alignment\":\"" << (options.with_scale ? "sim" : "se") << (options.planar ? "2" : "3")
       << "\",\"scale\":" << jsonNumber(r.alignment.scale)
       << ",\"yaw_deg\":" << jsonNumber(r.alignment.yaw() * 180.0 / M_PI) << ",\"ate\":{\"rmse\":"
       << jsonNumber(r.ate.rmse) << ",\"mean\":" << jsonNumber(r.ate.mean)
       << ",\"median\":" << jsonNumber(r.ate.median) << ",\"max\":" << jsonNumber(r.ate.max)
       << "},\"path_length\":" << jsonNumber(r.path_length)
       << ",\"drift_percent\":" << jsonNumber(r.drift_percent) << ",\"drift_segments\":[";
  for (std::size_t k = 0; k < r.drift.size(); ++k) {
    json << (k ? "," : "") << "{\"length\":" << jsonNumber(r.drift[k].length)
         << ",\"count\":" << r.drift[k].count
         << ",\"mean_percent\":" << jsonNumber(r.drift[k].count ? r.drift[k].mean_percent : std::nan(""))
         << "}";
  }
  json << "],\"loop_error\":" << jsonNumber(r.loop_error)
       << ",\"loop_error_percent\":" << jsonNumber(r.loop_error_percent)
       << ",\"heading_steps\":{\"count\":" << r.heading_steps.count
       << ",\"rmse_deg\":" << jsonNumber(r.heading_steps.rmse * 180.0 / M_PI)
       << ",\"max_deg\":" << jsonNumber(r.heading_steps.max * 180.0 / M_PI)
       << ",\"threshold_deg\":" << jsonNumber(options.heading_step_threshold * 180.0 / M_PI)
       << ",\"over_threshold\":" << r.heading_steps.over_threshold << "}}";
  return json.str();
}

std::string evaluationTable(const EvaluationResult& r, const EvaluationOptions& options) {
  std::ostringstream out;
  auto row = [&out](const std::string& name, const std::string& value) {
    out << "  " << name << std::string(name.size() < 22 ? 22 - name.size() : 1, ' ') << value << "\n";
  };
  row("poses", std::to_string(r.matched) + " matched (" + std::to_string(r.estimate_poses) +
                   " estimated, " + std::to_string(r.truth_poses) + " ground truth, " +
                   (options.association == AssociationMode::kIndex ? "by index" : "by timestamp") + ")");
  row("alignment", std::string(options.with_scale ? "similarity" : "rigid") +
                       (options.planar ? " in x-y" : " in 3-D") + ", scale " +
                       format("%.6g", r.alignment.scale) + ", yaw " +
                       format("%.3f deg", r.alignment.yaw() * 180.0 / M_PI));
  row("path length", format("%.3f m", r.path_length));
  row("ATE rmse", format("%.4f m", r.ate.rmse));
  row("ATE mean", format("%.4f m", r.ate.mean));
  row("ATE median", format("%.4f m", r.ate.median));
  row("ATE max", format("%.4f m", r.ate.max));
  for (const DriftSegment& s : r.drift) {
    row("drift over " + format("%.1f m", s.length),
        s.count ? format("%.3f %%", s.mean_percent) + " (" + std::to_string(s.count) + " segments)" : "n/a");
  }
  row("drift (all segments)", std::isfinite(r.drift_percent) ? format("%.3f %%", r.drift_percent) : "n/a");
  row("loop error", format("%.4f m", r.loop_error) + " (" + format("%.3f %%", r.loop_error_percent) +
                        " of the path)");
  row("heading steps", std::to_string(r.heading_steps.count) + ", error rmse " +
                           format("%.3f deg", r.heading_steps.rmse * 180.0 / M_PI) + ", max " +
                           format("%.3f deg", r.heading_steps.max * 180.0 / M_PI) + ", " +
                           std::to_string(r.heading_steps.over_threshold) + " over " +
                           format("%g deg", options.heading_step_threshold * 180.0 / M_PI));
  return out.str();
}

}  // namespace oefmt
