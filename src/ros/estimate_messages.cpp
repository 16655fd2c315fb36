// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/ros/estimate_messages.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <vector>

#include <opencv2/imgproc.hpp>

namespace oefmt {
namespace {

constexpr double kUnobservedVariance = 1e6;  // roll, pitch and their rates
constexpr double kMinVariance = 1e-6;         // never publish a zero variance

void setQuaternion(double yaw, geometry_msgs::Quaternion& q) {
  const auto values = yawQuaternion(yaw);
  q.x = values[0];
  q.y = values[1];
  q.z = values[2];
  q.w = values[3];
}

std::vector<float> toFloat(const std::vector<float>& v) { return v; }

}  // namespace

Pose4 rotatedPose(const Pose4& pose, double mount_yaw) {
  if (mount_yaw == 0.0) return pose;
  const double c = std::cos(mount_yaw), s = std::sin(mount_yaw);
  Pose4 out = pose;
  out.x = c * pose.x - s * pose.y;
  out.y = s * pose.x + c * pose.y;
  cv::Matx44d rotation = cv::Matx44d::eye();
  rotation(0, 0) = c;
  rotation(0, 1) = -s;
  rotation(1, 0) = s;
  rotation(1, 1) = c;
  out.covariance = rotation * pose.covariance * rotation.t();
  return out;
}

nav_msgs::Odometry odometryMessage(const Pose4& pose, const Pose4* previous,
                                   const std_msgs::Header& header, const std::string& child_frame) {
  nav_msgs::Odometry odometry;
  odometry.header = header;
  odometry.child_frame_id = child_frame;
  odometry.pose.pose.position.x = pose.x;
  odometry.pose.pose.position.y = pose.y;
  odometry.pose.pose.position.z = pose.z;
  setQuaternion(pose.yaw, odometry.pose.pose.orientation);
  const auto covariance = covariance6x6(pose, kUnobservedVariance, kMinVariance);
  std::copy(covariance.begin(), covariance.end(), odometry.pose.covariance.begin());

  // Twist in the child frame, by finite difference; variances from the pose covariance growth.
  auto& twist = odometry.twist.covariance;
  std::fill(twist.begin(), twist.end(), 0.0);
  const double dt = previous != nullptr ? pose.stamp - previous->stamp : 0.0;
  if (previous != nullptr && dt > 0.0 && std::isfinite(dt)) {
    const double dx = pose.x - previous->x, dy = pose.y - previous->y;
    const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
    odometry.twist.twist.linear.x = (c * dx + s * dy) / dt;
    odometry.twist.twist.linear.y = (-s * dx + c * dy) / dt;
    odometry.twist.twist.linear.z = (pose.z - previous->z) / dt;
    odometry.twist.twist.angular.z = std::remainder(pose.yaw - previous->yaw, 2.0 * M_PI) / dt;
    const int axes[4] = {0, 1, 2, 5};
    for (int i = 0; i < 4; ++i) {
      const double growth = pose.covariance(i, i) - previous->covariance(i, i);
      twist[axes[i] * 7] = std::max(growth / (dt * dt), kMinVariance);
    }
    twist[3 * 7] = twist[4 * 7] = kUnobservedVariance;
  } else {
    for (int i = 0; i < 6; ++i) twist[i * 7] = kUnobservedVariance;
  }
  return odometry;
}

geometry_msgs::TransformStamped transformMessage(const Pose4& pose, const std_msgs::Header& header,
                                                 const std::string& child_frame) {
  geometry_msgs::TransformStamped transform;
  transform.header = header;
  transform.child_frame_id = child_frame;
  transform.transform.translation.x = pose.x;
  transform.transform.translation.y = pose.y;
  transform.transform.translation.z = pose.z;
  setQuaternion(pose.yaw, transform.transform.rotation);
  return transform;
}

oefmt::EnergyVectors energyVectorsMessage(const Estimate& estimate, double log_zoom_per_bin,
                                          double shift_per_bin, const std_msgs::Header& header) {
  oefmt::EnergyVectors m;
  m.header = header;
  const PairRegistration& r = estimate.registration12;
  m.zoom_energy = toFloat(r.zoom_energy);
  m.translation_energy = toFloat(r.translation_energy);
  if (estimate.has_registration02) {
    m.zoom_energy_02 = estimate.registration02.zoom_energy;
    m.translation_energy_02 = estimate.registration02.translation_energy;
  }
  m.log_zoom_bin = log_zoom_per_bin;
  m.translation_bin_px = shift_per_bin;
  m.rotation = r.rotation;
  m.zoom = r.zoom;
  m.direction = r.direction;
  m.shift = r.shift;
  m.rotation_sigma = r.rotation_sigma;
  m.log_zoom_sigma = r.log_zoom_sigma;
  m.direction_sigma = r.direction_sigma;
  m.shift_sigma = r.shift_sigma;
  m.confidence = r.confidence;
  m.pmt12 = estimate.pmt12.value;
  m.pmt12_sigma = estimate.pmt12.sigma;
  m.pmt02 = estimate.pmt02.value;
  m.pmt02_sigma = estimate.pmt02.sigma;
  m.pms12 = estimate.pms12.value;
  m.pms12_sigma = estimate.pms12.sigma;
  m.pms02 = estimate.pms02.value;
  m.pms02_sigma = estimate.pms02.sigma;
  m.mode = toString(estimate.mode);
  m.tracking_state = toString(estimate.state);
  m.optimizer_status = toString(estimate.loop.status);
  m.optimizer_iterations = estimate.loop.iterations;
  m.optimizer_initial_cost = estimate.loop.initial_cost;
  m.optimizer_final_cost = estimate.loop.final_cost;
  m.processing_ms = estimate.total_ms;
  return m;
}

namespace {

// Draws v (first `bins` values) as a polyline into the panel, scaled to its maximum.
void plotVector(cv::Mat& image, const cv::Rect& panel, const std::vector<float>& v, int first,
                int bins, const cv::Scalar& colour) {
  if (v.empty() || bins < 2) return;
  const int end = std::min<int>(first + bins, static_cast<int>(v.size()));
  float top = 0.0f;
  for (int j = first; j < end; ++j) top = std::max(top, v[j]);
  if (!(top > 0.0f)) return;
  std::vector<cv::Point> points;
  for (int j = first; j < end; ++j) {
    const int x = panel.x + (j - first) * (panel.width - 1) / (bins - 1);
    const int y = panel.y + panel.height - 1 - static_cast<int>(v[j] / top * (panel.height - 12));
    points.push_back({x, y});
  }
  cv::polylines(image, points, false, colour, 2, cv::LINE_AA);
}

}  // namespace

cv::Mat renderEnergyVectors(const Estimate& estimate, double shift_per_bin, cv::Size size) {
  cv::Mat image(size, CV_8UC3, cv::Scalar(30, 30, 30));
  const int margin = 10, title = 22;
  const int panel_height = (size.height - 3 * margin - 2 * title) / 2;
  const cv::Rect zoom_panel(margin, margin + title, size.width - 2 * margin, panel_height);
  const cv::Rect shift_panel(margin, zoom_panel.br().y + margin + title, size.width - 2 * margin,
                             panel_height);
  for (const cv::Rect& panel : {zoom_panel, shift_panel}) {
    cv::rectangle(image, panel, cv::Scalar(80, 80, 80), 1);
  }
  const cv::Scalar colour12(60, 200, 255), colour02(255, 160, 60);
  const auto& r12 = estimate.registration12;
  const auto& r02 = estimate.registration02;
  // Zoom vectors: the central quarter of the bins (zooms within about +-35 %).
  const int zoom_bins = std::max<int>(2, static_cast<int>(r12.zoom_energy.size()) / 4);
  const int zoom_first = static_cast<int>(r12.zoom_energy.size()) / 2 - zoom_bins / 2;
  plotVector(image, zoom_panel, r12.zoom_energy, zoom_first, zoom_bins, colour12);
  // Translation vectors: up to the farther of the two peaks, with room.
  int shift_bins = 16;
  for (const auto* r : {&r12, &r02}) {
    if (!r->translation_energy.empty()) {
      shift_bins = std::max(shift_bins, static_cast<int>(2.5 * r->shift / shift_per_bin));
    }
  }
  shift_bins = std::min<int>(shift_bins, static_cast<int>(r12.translation_energy.size()));
  plotVector(image, shift_panel, r12.translation_energy, 0, shift_bins, colour12);
  if (estimate.has_registration02) {
    plotVector(image, zoom_panel, r02.zoom_energy, zoom_first, zoom_bins, colour02);
    plotVector(image, shift_panel, r02.translation_energy, 0, shift_bins, colour02);
  }
  char text[200];
  std::snprintf(text, sizeof(text), "zoom S (1-2 orange, 0-2 blue)  s12 %.4f  PMS12 %.2f  PMS02 %.2f bins",
                r12.zoom, estimate.pms12.value, estimate.pms02.value);
  cv::putText(image, text, {margin, margin + 15}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(230, 230, 230), 1, cv::LINE_AA);
  std::snprintf(text, sizeof(text), "translation T (0..%.0f px)  rho12 %.1f px  PMT12 %.3f  PMT02 %.3f  %s",
                shift_bins * shift_per_bin, r12.shift, estimate.pmt12.value, estimate.pmt02.value,
                toString(estimate.loop.status));
  cv::putText(image, text, {margin, zoom_panel.br().y + margin + 15}, cv::FONT_HERSHEY_SIMPLEX, 0.5,
              cv::Scalar(230, 230, 230), 1, cv::LINE_AA);
  return image;
}

namespace {

// Colours of cbrt(t) for t = |v| / max|v| in [0, 1], indexed by the top 16 bits of t's float
// (exponent and 7 mantissa bits: t is known to 1/256, its cube root to 1/768 — under one of the
// 256 levels). One table lookup per pixel instead of three passes (pow, normalise, colour map):
// the surfaces are rendered for every frame while subscribed, so the cost counts.
constexpr std::uint32_t kOneTopBits = 0x3F80;  // top 16 bits of 1.0f

const std::vector<cv::Vec3b>& cubeRootHeatTable() {
  static const std::vector<cv::Vec3b> table = [] {
    cv::Mat1b ramp(1, 256);
    for (int g = 0; g < 256; ++g) ramp(0, g) = static_cast<uchar>(g);
    cv::Mat colours;
    cv::applyColorMap(ramp, colours, cv::COLORMAP_INFERNO);
    std::vector<cv::Vec3b> entries(kOneTopBits + 1);
    for (std::uint32_t i = 0; i <= kOneTopBits; ++i) {
      const std::uint32_t bits = (i << 16) | 0x8000u;  // the middle of the bucket
      float t = 0.0f;
      std::memcpy(&t, &bits, sizeof(t));
      const int grey = static_cast<int>(std::lround(255.0 * std::cbrt(std::min(1.0f, t))));
      entries[i] = colours.at<cv::Vec3b>(0, std::clamp(grey, 0, 255));
    }
    entries[0] = colours.at<cv::Vec3b>(0, 0);  // 0 and denormals: black
    return entries;
  }();
  return table;
}

}  // namespace

cv::Mat renderSurface(const cv::Mat1f& surface) {
  if (surface.empty()) return cv::Mat();
  const std::vector<cv::Vec3b>& table = cubeRootHeatTable();
  double low = 0.0, high = 0.0;
  cv::minMaxLoc(surface, &low, &high);
  const double top = std::max(std::fabs(low), std::fabs(high));
  const float scale = top > 0.0 && std::isfinite(top) ? static_cast<float>(1.0 / top) : 0.0f;
  cv::Mat3b colour(surface.size());
  for (int r = 0; r < surface.rows; ++r) {
    const float* in = surface[r];
    cv::Vec3b* out = colour[r];
    for (int c = 0; c < surface.cols; ++c) {
      const float t = std::fabs(in[c]) * scale;
      std::uint32_t bits = 0;
      std::memcpy(&bits, &t, sizeof(bits));
      // NaN (and values rounding above 1) take the top colour.
      out[c] = table[std::min(bits >> 16, kOneTopBits)];
    }
  }
  return colour;
}

}  // namespace oefmt
