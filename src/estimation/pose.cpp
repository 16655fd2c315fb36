// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/estimation/pose.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <ostream>

#include <Eigen/Core>

#include "oefmt/error.h"

namespace oefmt {

bool Pose4::finite() const {
  if (!std::isfinite(stamp) || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z) ||
      !std::isfinite(yaw)) {
    return false;
  }
  for (int i = 0; i < 16; ++i) {
    if (!std::isfinite(covariance.val[i])) return false;
  }
  return true;
}

std::array<double, 36> covariance6x6(const Pose4& pose, double unobserved_variance,
                                     double min_variance) {
  std::array<double, 36> out{};
  // Pose4 index -> 6x6 index: x, y, z stay, yaw goes to 5.
  const int map[4] = {0, 1, 2, 5};
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) out[map[r] * 6 + map[c]] = pose.covariance(r, c);
  }
  out[3 * 6 + 3] = unobserved_variance;
  out[4 * 6 + 4] = unobserved_variance;
  for (int i = 0; i < 6; ++i) {
    double& v = out[i * 6 + i];
    if (!(v >= min_variance)) v = std::isfinite(v) ? min_variance : unobserved_variance;
  }
  return out;
}

std::array<double, 4> yawQuaternion(double yaw) {
  return {0.0, 0.0, std::sin(0.5 * yaw), std::cos(0.5 * yaw)};
}

PoseIntegrator::PoseIntegrator(double initial_altitude, double fx)
    : initial_altitude_(initial_altitude), fx_(fx) {
  if (!std::isfinite(initial_altitude) || !(initial_altitude > 0.0)) {
    throw InputError("PoseIntegrator: initial altitude must be finite and > 0");
  }
  if (!std::isfinite(fx) || !(fx > 0.0)) throw InputError("PoseIntegrator: fx must be finite and > 0");
}

void PoseIntegrator::reset(double stamp) {
  pose_ = Pose4{};
  pose_.stamp = stamp;
  plane_height_ = 0.0;
  last_step_covariance_ = cv::Matx44d::zeros();
}

void PoseIntegrator::moveReferencePlane(double depth_ratio) {
  if (!std::isfinite(depth_ratio) || !(depth_ratio > 0.0)) return;
  plane_height_ += altitude() * (1.0 - depth_ratio);
}

void PoseIntegrator::correctAltitude(double altitude, double variance) {
  if (!std::isfinite(altitude) || !(altitude > 0.0) || !std::isfinite(variance) || !(variance > 0.0)) return;
  const double prior = pose_.covariance(2, 2);
  // A pose with no variance yet (the first frame) takes the measurement as it is.
  const double gain = prior > 0.0 ? prior / (prior + variance) : 1.0;
  pose_.z += gain * (altitude - this->altitude());
  // Joseph-free form for a scalar measurement of one state: P <- P - K H P.
  const cv::Matx44d p = pose_.covariance;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) pose_.covariance(r, c) = p(r, c) - (prior > 0.0 ? p(r, 2) * p(2, c) / (prior + variance) : 0.0);
  }
}

const Pose4& PoseIntegrator::integrate(const PairMotion& step, double stamp) {
  using Mat4 = Eigen::Matrix4d;
  using Vec2 = Eigen::Vector2d;
  const double psi = wrapToPi(-pose_.yaw + step.rotation);
  const double inv_zoom = std::exp(-step.log_zoom);
  const double altitude = this->altitude() * inv_zoom;
  const double metres_per_px = altitude / fx_;
  const double c = std::cos(psi), s = std::sin(psi);
  Eigen::Matrix2d rotation;
  rotation << c, -s, s, c;
  const Vec2 v = rotation * Vec2(step.translation.x, step.translation.y);  // R(psi) d
  const Vec2 v_turned(-v.y(), v.x());                                      // d/dpsi of R(psi) d
  const Vec2 image_step = -metres_per_px * v;
  const Eigen::Matrix2d flip = Eigen::Vector2d(1.0, -1.0).asDiagonal();  // image y down -> north

  // First-order propagation over state (x, y, z, yaw) and inputs (theta, ln s, dx, dy).
  Mat4 f = Mat4::Identity();
  f.block<2, 1>(0, 3) = flip * (metres_per_px * v_turned);  // yaw = -psi
  f.block<2, 1>(0, 2) = flip * (-(inv_zoom / fx_) * v);
  f(2, 2) = inv_zoom;
  Mat4 g = Mat4::Zero();
  g.block<2, 1>(0, 0) = flip * (-metres_per_px * v_turned);
  g.block<2, 1>(0, 1) = flip * (metres_per_px * v);
  g.block<2, 2>(0, 2) = flip * (-metres_per_px * rotation);
  g(2, 1) = -altitude;
  g(3, 0) = -1.0;
  Mat4 q = Mat4::Zero();
  q(0, 0) = step.rotation_sigma * step.rotation_sigma;
  q(1, 1) = step.log_zoom_sigma * step.log_zoom_sigma;
  for (int r = 0; r < 2; ++r) {
    for (int col = 0; col < 2; ++col) q(2 + r, 2 + col) = step.translation_covariance(r, col);
  }
  Mat4 sigma;
  for (int r = 0; r < 4; ++r) {
    for (int col = 0; col < 4; ++col) sigma(r, col) = pose_.covariance(r, col);
  }
  Mat4 added = g * q * g.transpose();
  added = 0.5 * (added + added.transpose());
  Mat4 next = f * sigma * f.transpose() + added;
  next = 0.5 * (next + next.transpose());

  const Vec2 world_step = flip * image_step;
  pose_.x += world_step.x();
  pose_.y += world_step.y();
  pose_.z = altitude + plane_height_ - initial_altitude_;
  pose_.yaw = wrapToPi(-psi);
  pose_.stamp = stamp;
  for (int r = 0; r < 4; ++r) {
    for (int col = 0; col < 4; ++col) {
      pose_.covariance(r, col) = next(r, col);
      last_step_covariance_(r, col) = added(r, col);
    }
  }
  return pose_;
}

void PoseIntegrator::rescale(double factor) {
  if (!std::isfinite(factor) || !(factor > 0.0)) return;
  initial_altitude_ *= factor;
  plane_height_ *= factor;
  pose_ = rescaled(pose_, factor);
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) {
      last_step_covariance_(r, c) *= (r < 3 ? factor : 1.0) * (c < 3 ? factor : 1.0);
    }
  }
}

Pose4 rescaled(const Pose4& pose, double factor) {
  Pose4 out = pose;
  out.x *= factor;
  out.y *= factor;
  out.z *= factor;
  for (int r = 0; r < 4; ++r) {
    for (int c = 0; c < 4; ++c) out.covariance(r, c) *= (r < 3 ? factor : 1.0) * (c < 3 ? factor : 1.0);
  }
  return out;
}

const Pose4& PoseIntegrator::hold(double stamp, const cv::Matx44d& extra_covariance) {
  pose_.stamp = stamp;
  pose_.covariance += extra_covariance;
  last_step_covariance_ = extra_covariance;
  return pose_;
}

}  // namespace oefmt
