// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/estimation/attitude.h"

#include <algorithm>
#include <cmath>

namespace oefmt {
namespace {

// The optical frame turned 180 degrees about x: the camera body (and back; its own inverse).
const Eigen::Matrix3d& flipX() {
  static const Eigen::Matrix3d flip = Eigen::Vector3d(1.0, -1.0, -1.0).asDiagonal();
  return flip;
}

Eigen::Matrix3d tiltRotation(const CameraTilt& tilt) {
  return (Eigen::AngleAxisd(tilt.pitch, Eigen::Vector3d::UnitY()) * Eigen::AngleAxisd(tilt.roll, Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

}  // namespace

double tiltAngle(const CameraTilt& tilt) {
  return std::acos(std::clamp(std::cos(tilt.roll) * std::cos(tilt.pitch), -1.0, 1.0));
}

void addUnknownTilt(std::array<double, 36>& covariance, double altitude, double tilt_sigma) {
  if (!std::isfinite(altitude) || !std::isfinite(tilt_sigma) || !(tilt_sigma > 0.0)) return;
  const double shift = std::fabs(altitude) * std::tan(std::min(tilt_sigma, 0.49 * M_PI));
  covariance[0 * 6 + 0] += shift * shift;
  covariance[1 * 6 + 1] += shift * shift;
  for (const int axis : {3, 4}) covariance[axis * 6 + axis] = tilt_sigma * tilt_sigma;
}

CameraTilt cameraTilt(const Eigen::Matrix3d& world_from_optical) {
  const Eigen::Matrix3d body = world_from_optical * flipX();
  // Rz(yaw) Ry(pitch) Rx(roll): row 2 is (-sin p, cos p sin r, cos p cos r), free of the yaw.
  CameraTilt tilt;
  tilt.pitch = std::asin(std::clamp(-body(2, 0), -1.0, 1.0));
  tilt.roll = std::atan2(body(2, 1), body(2, 2));
  return tilt;
}

Eigen::Matrix3d nadirFromOptical(const CameraTilt& tilt) {
  // world <- virtual optical = Rz(yaw) F, world <- optical = Rz(yaw) T F (F = flipX, T the tilt):
  // virtual <- optical = F T F.
  return flipX() * tiltRotation(tilt) * flipX();
}

Eigen::Vector2d opticalAxisInNadirView(const CameraTilt& tilt, double fx) {
  const Eigen::Vector3d axis = nadirFromOptical(tilt) * Eigen::Vector3d::UnitZ();
  if (!(axis.z() > 1e-6) || !std::isfinite(fx)) return Eigen::Vector2d::Zero();
  return Eigen::Vector2d(fx * axis.x() / axis.z(), fx * axis.y() / axis.z());
}

Eigen::Quaterniond cameraBodyOrientation(double yaw, const CameraTilt& tilt) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw, Eigen::Vector3d::UnitZ()) * tiltRotation(tilt)).normalized();
}

Eigen::Matrix3d downLookingMount() { return flipX(); }

std::optional<CameraTilt> cameraTiltAt(const AttitudeHistory& body, double stamp,
                                       const Eigen::Matrix3d& body_from_optical) {
  const std::optional<Eigen::Quaterniond> orientation = body.at(stamp);
  if (!orientation) return std::nullopt;
  return cameraTilt(orientation->toRotationMatrix() * body_from_optical);
}

AttitudeHistory::AttitudeHistory(double max_gap) : max_gap_(max_gap) {}

bool AttitudeHistory::add(double stamp, const Eigen::Quaterniond& body_to_world) {
  if (!std::isfinite(stamp) || !body_to_world.coeffs().allFinite() || !(body_to_world.norm() > 1e-6)) return false;
  if (!samples_.empty() && !(stamp > samples_.back().stamp)) return false;
  samples_.push_back({stamp, body_to_world.normalized()});
  return true;
}

std::optional<Eigen::Quaterniond> AttitudeHistory::at(double stamp) const {
  const auto after = std::lower_bound(samples_.begin(), samples_.end(), stamp,
                                      [](const Sample& s, double t) { return s.stamp < t; });
  if (after == samples_.end()) return std::nullopt;
  if (after->stamp == stamp) return after->orientation;
  if (after == samples_.begin()) return std::nullopt;
  const Sample& before = *(after - 1);
  const double span = after->stamp - before.stamp;
  if (!(span <= max_gap_)) return std::nullopt;
  return before.orientation.slerp((stamp - before.stamp) / span, after->orientation);
}

void AttitudeHistory::forgetBefore(double stamp) {
  // Keep the last sample before `stamp`: it brackets stamps just after it.
  while (samples_.size() > 1 && samples_[1].stamp <= stamp) samples_.pop_front();
}

TurnHistory::TurnHistory(double max_gap, const Eigen::Matrix3d& imu_from_body)
    : max_gap_(max_gap), imu_from_body_(imu_from_body) {}

bool TurnHistory::add(double stamp, const Eigen::Quaterniond& imu_to_world, const Eigen::Vector3d& imu_rates) {
  if (!std::isfinite(stamp) || (!samples_.empty() && !(stamp > samples_.back().stamp))) return false;
  const Eigen::Matrix3d r = imu_to_world.normalized().toRotationMatrix() * imu_from_body_;
  const Eigen::Vector3d angular_velocity = imu_from_body_.transpose() * imu_rates;
  // The yaw's rate (yaw, pitch, roll about z, y', x''), the one angle the level view keeps: from
  // the body rates p, q, r, yaw' = (q sin roll + r cos roll) / cos pitch. (The world's vertical
  // rate is not it: a roll while pitched turns about it without changing the yaw.)
  const double pitch = std::asin(std::clamp(-r(2, 0), -1.0, 1.0));
  const double roll = std::atan2(r(2, 1), r(2, 2));
  const double rate = (angular_velocity.y() * std::sin(roll) + angular_velocity.z() * std::cos(roll)) /
                      std::max(std::cos(pitch), 1e-6);
  if (!std::isfinite(rate)) return false;
  samples_.push_back({stamp, rate});
  return true;
}

std::optional<double> TurnHistory::turn(double from, double to) const {
  if (!(to >= from) || samples_.empty() || samples_.front().stamp > from || samples_.back().stamp < to) {
    return std::nullopt;
  }
  // The rate at t on the segment a-b, linearly.
  const auto rateAt = [](const Sample& a, const Sample& b, double t) {
    const double span = b.stamp - a.stamp;
    return span > 0.0 ? a.rate + (b.rate - a.rate) * (t - a.stamp) / span : a.rate;
  };
  if (samples_.size() == 1) return from == to ? std::optional<double>(0.0) : std::nullopt;
  double turned = 0.0;
  for (std::size_t k = 1; k < samples_.size(); ++k) {
    const Sample& a = samples_[k - 1];
    const Sample& b = samples_[k];
    if (b.stamp <= from) continue;
    if (a.stamp >= to) break;
    if (b.stamp - a.stamp > max_gap_) return std::nullopt;
    const double t0 = std::max(a.stamp, from), t1 = std::min(b.stamp, to);
    turned += 0.5 * (rateAt(a, b, t0) + rateAt(a, b, t1)) * (t1 - t0);
  }
  return turned;
}

void TurnHistory::forgetBefore(double stamp) {
  while (samples_.size() > 1 && samples_[1].stamp <= stamp) samples_.pop_front();
}

}  // namespace oefmt
