// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/sim/track.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "oefmt/error.h"

namespace oefmt {
namespace sim {
namespace {

// The track's shape at unit size, u in [0, 1].
cv::Point2d unitShape(const TrackConfig& config, double u) {
  const double a = 2.0 * CV_PI * u;
  switch (config.shape) {
    case TrackShape::kCircle: return {std::cos(a), std::sin(a)};
    case TrackShape::kEight: return {std::sin(a), std::sin(a) * std::cos(a)};
    case TrackShape::kLine:
    case TrackShape::kSpin: break;
  }
  return {u * std::cos(config.line_direction), u * std::sin(config.line_direction)};
}

// Speed |d shape / du| of the unit shape.
double unitSpeed(const TrackConfig& config, double u) {
  const double a = 2.0 * CV_PI * u;
  switch (config.shape) {
    case TrackShape::kCircle: return 2.0 * CV_PI;
    case TrackShape::kEight: return 2.0 * CV_PI * std::hypot(std::cos(a), std::cos(2.0 * a));
    case TrackShape::kLine:
    case TrackShape::kSpin: break;
  }
  return 1.0;
}

}  // namespace

// Arc length of the unit shape at u = k / (samples - 1) (Simpson's rule on the speed: exact for
// the circle and the line), to walk it at constant speed.
struct ArcTable {
  std::vector<double> u;
  std::vector<double> length;

  explicit ArcTable(const TrackConfig& config, int samples = 20001) {
    u.resize(samples);
    length.resize(samples, 0.0);
    for (int k = 0; k < samples; ++k) {
      u[k] = static_cast<double>(k) / (samples - 1);
      if (k == 0) continue;
      const double h = u[k] - u[k - 1];
      length[k] = length[k - 1] + h / 6.0 *
                                      (unitSpeed(config, u[k - 1]) + 4.0 * unitSpeed(config, u[k - 1] + h / 2.0) +
                                       unitSpeed(config, u[k]));
    }
  }
  double total() const { return length.back(); }
  // u at arc length s (linear between samples).
  double at(double s) const {
    const auto it = std::lower_bound(length.begin(), length.end(), s);
    if (it == length.begin()) return 0.0;
    if (it == length.end()) return 1.0;
    const std::size_t k = static_cast<std::size_t>(it - length.begin());
    const double span = length[k] - length[k - 1];
    const double f = span > 0.0 ? (s - length[k - 1]) / span : 0.0;
    return u[k - 1] + f * (u[k] - u[k - 1]);
  }
};

void TrackConfig::validate() const {
  if (isMoving(shape)) {
    requireInput(length > 0.0 && std::isfinite(length), "track: length must be > 0");
  } else {
    requireInput(climb == 0.0, "track: a spin does not climb (climb must be 0)");
    requireInput(heading == HeadingMode::kFixed, "track: a spin does not move: its heading cannot follow the track");
  }
  requireInput(frames >= 2, "track: frames must be >= 2");
  requireInput(altitude > 0.0 && std::isfinite(altitude), "track: altitude must be > 0");
  requireInput(std::isfinite(climb) && altitude + climb > 0.0, "track: altitude + climb must stay > 0");
  requireInput(!(climb_profile == ClimbProfile::kRamp && isClosed(shape)),
               "track: a loop must come back to its start: climb profile ramp needs a line track");
  requireInput(std::isfinite(yaw) && std::isfinite(line_direction), "track: angles must be finite");
  requireInput(std::isfinite(spin_rate) && std::fabs(spin_rate) < CV_PI, "track: spin rate must be in (-180, 180) deg");
}

bool isClosed(TrackShape shape) { return shape == TrackShape::kCircle || shape == TrackShape::kEight; }

bool isMoving(TrackShape shape) { return shape != TrackShape::kSpin; }

ClimbProfile resolvedClimbProfile(const TrackConfig& config) {
  if (config.climb_profile != ClimbProfile::kAuto) return config.climb_profile;
  return isClosed(config.shape) ? ClimbProfile::kHill : ClimbProfile::kRamp;
}

double frameSpacing(const TrackConfig& config) {
  return isMoving(config.shape) ? config.length / (config.frames - 1) : 0.0;
}

TrackPath::TrackPath(const TrackConfig& config) : config_(config) {
  config_.validate();
  if (isMoving(config_.shape)) {
    table_ = std::make_shared<const ArcTable>(config_);
    scale_ = config_.length / table_->total();
  }
}

FlightPose TrackPath::at(double k) const {
  FlightPose pose;
  if (!isMoving(config_.shape)) {
    pose.position = cv::Vec3d(0.0, 0.0, config_.altitude);
    pose.yaw = std::remainder(config_.yaw + k * config_.spin_rate, 2.0 * CV_PI);
    return pose;
  }
  const double last = config_.frames - 1;
  double s = k == last ? config_.length : k * frameSpacing(config_);  // exact closure
  if (isClosed(config_.shape) && (s < 0.0 || s > config_.length)) {
    s -= config_.length * std::floor(s / config_.length);  // loops repeat
  }
  const double fraction = s / config_.length;
  // Lines go on straight beyond their ends (the arc table covers the track itself).
  const double u = s >= 0.0 && s <= config_.length ? table_->at(s / scale_) : s / config_.length;
  const cv::Point2d p = unitShape(config_, u) * scale_;
  const bool hill = resolvedClimbProfile(config_) == ClimbProfile::kHill;
  const double profile = hill ? 0.5 * (1.0 - std::cos(2.0 * CV_PI * fraction)) : fraction;
  pose.position = cv::Vec3d(p.x, p.y, config_.altitude + config_.climb * profile);
  pose.yaw = config_.yaw;
  if (config_.heading == HeadingMode::kTrack) {
    // Direction of motion from a short chord around u (the shapes are smooth).
    const double du = 1e-5;
    const bool line = !isClosed(config_.shape);
    const cv::Point2d ahead = unitShape(config_, line && u > 1.0 ? u + du : std::min(1.0, u + du));
    const cv::Point2d behind = unitShape(config_, line && u < 0.0 ? u - du : std::max(0.0, u - du));
    pose.yaw += std::atan2(ahead.y - behind.y, ahead.x - behind.x);
    pose.yaw = std::remainder(pose.yaw, 2.0 * CV_PI);
  }
  return pose;
}

std::vector<FlightPose> makeTrack(const TrackConfig& config) {
  const TrackPath path(config);
  std::vector<FlightPose> poses;
  for (int k = 0; k < config.frames; ++k) poses.push_back(path.at(k));
  if (isClosed(config.shape)) {
    poses.back() = poses.front();  // bit-identical loop closure
  }
  return poses;
}

}  // namespace sim
}  // namespace oefmt
