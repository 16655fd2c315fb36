// SPDX-License-Identifier: GPL-3.0-or-later
// The separable apodization window (doc/method.md, The frame's spectra): stored as one N-vector,
// not an N x N image.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace oefmt {

class SeparableWindow {
 public:
  SeparableWindow() = default;
  /// Hann halves of length 2R at both ends (R = floor(taper_fraction * n)), 1 inside.
  SeparableWindow(int n, double taper_fraction);

  int size() const { return static_cast<int>(taper_.size()); }
  /// w(row, col) = taper(row) * taper(col).
  float operator()(int row, int col) const { return taper_[row] * taper_[col]; }
  /// The 1-D taper, one value per row or column.
  const std::vector<float>& taper() const { return taper_; }
  /// out = (in - offset) * w (element-wise); in and out may be the same image. Subtracting the
  /// image mean first keeps the window's own shape out of the spectrum (it would correlate at
  /// zero shift between any two frames).
  void apply(const cv::Mat1f& in, cv::Mat1f& out, float offset = 0.0f) const;
  /// The share of the windowed energy that two frames shifted by `shift` [px] have in common
  /// (1 at zero shift): a perfect match's correlation peak grows with it.
  double overlapShare(const cv::Point2d& shift) const;

 private:
  std::vector<float> taper_;
  std::vector<double> overlap_share_;  // per shift of 0 .. n - 1 cells along one axis
};

}  // namespace oefmt
