// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/registration/window.h"

#include <algorithm>
#include <cmath>

#include "oefmt/error.h"

namespace oefmt {

SeparableWindow::SeparableWindow(int n, double taper_fraction) : taper_(static_cast<size_t>(n), 1.0f) {
  const int taper = static_cast<int>(std::floor(taper_fraction * n));
  for (int i = 0; i < taper; ++i) {
    const float h = static_cast<float>(0.5 - 0.5 * std::cos(2.0 * CV_PI * i / (2.0 * taper - 1.0)));
    taper_[i] = h;
    taper_[n - 1 - i] = h;
  }
  overlap_share_.assign(static_cast<size_t>(n), 0.0);
  for (int shift = 0; shift < n; ++shift) {
    for (int i = 0; i + shift < n; ++i) overlap_share_[shift] += double(taper_[i]) * taper_[i + shift];
  }
  const double whole = n > 0 ? overlap_share_[0] : 0.0;
  for (double& share : overlap_share_) share = whole > 0.0 ? share / whole : 0.0;
}

double SeparableWindow::overlapShare(const cv::Point2d& shift) const {
  const int n = size();
  if (n == 0) return 1e-12;
  const auto cell = [n](double v) { return std::min(static_cast<int>(std::lround(std::fabs(v))), n - 1); };
  return std::max(overlap_share_[cell(shift.x)] * overlap_share_[cell(shift.y)], 1e-12);
}

void SeparableWindow::apply(const cv::Mat1f& in, cv::Mat1f& out, float offset) const {
  if (in.rows != size() || in.cols != size()) throw InputError("window: image of the wrong size");
  out.create(in.size());
  const float* t = taper_.data();
  for (int r = 0; r < in.rows; ++r) {
    const float* src = in[r];
    float* dst = out[r];
    const float row_weight = t[r];
    for (int c = 0; c < in.cols; ++c) dst[c] = (src[c] - offset) * row_weight * t[c];
  }
}

}  // namespace oefmt
