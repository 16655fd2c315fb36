// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/registration/block_motion.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"
#include "oefmt/registration/phase_correlation.h"
#include "oefmt/registration/robust_statistics.h"
#include "oefmt/registration/warp.h"

namespace oefmt {
namespace {

// The blocks' side is the frame's over kBlocksPerSide (seven of them fit a side within the
// margin [px] kept from the frame's edge, where the apodization and the sampling's interpolation
// leave too little texture).
constexpr int kBlocksPerSide = 8;
constexpr int kEdgeMargin = 8;
// A block follows the pair's motion when its remaining shift lies within this many pixels: the
// similarity it is sampled at is within a pixel or two at the image's edge, while another depth
// layer or a periodic texture's alias lies further off.
constexpr double kFollowRadius = 3.0;
// A block's phase correlation peak must reach this height (of 1 for a perfect match): unrelated
// 64-pixel blocks peak at about 0.05-0.1.
constexpr double kMinBlockPeak = 0.15;
// Fewest following blocks that read a rotation and zoom: four unknowns, two readings a block.
constexpr int kMinBlocks = 4;
// The fit's robust weights: Tukey's biweight at this many robust scatters, over this many passes;
// the scatter's floor per component [px] (a rigid layer's blocks agree to a few hundredths of a
// pixel).
constexpr double kTukeyScatters = 4.685;
constexpr int kFitPasses = 5;
constexpr double kAxisScatterFloor = 0.02;
// Below this shift [px] its direction, and with it "across the motion", is not known.
constexpr double kMinAcrossShift = 1.0;

// Sub-pixel offset of a peak from its two neighbours: a Gaussian through the three where all are
// positive (the shape of a windowed correlation peak), else a parabola.
double peakOffset(float before, float at, float after) {
  if (before > 0.0f && at > 0.0f && after > 0.0f) {
    const double lb = std::log(before), la = std::log(at), lf = std::log(after);
    const double curvature = lb - 2.0 * la + lf;
    if (curvature < 0.0) return std::clamp(0.5 * (lb - lf) / curvature, -0.5, 0.5);
  }
  const double curvature = before - 2.0 * at + after;
  return curvature < 0.0 ? std::clamp(0.5 * (before - after) / curvature, -0.5, 0.5) : 0.0;
}

// The side of the blocks for frames of `image_size` pixels: an eighth, rounded down to even.
int blockSizeFor(int image_size) {
  if (image_size < BlockMotionReader::kMinImageSize) {
    throw InputError("BlockMotionReader: frames of " + std::to_string(image_size) + " px are under " +
                     std::to_string(BlockMotionReader::kMinImageSize) + " px");
  }
  return image_size / (2 * kBlocksPerSide) * 2;
}

// R readings of one block's shift: rows of the fit's K unknowns and the values they should give.
template <int K, int R>
struct BlockReadings {
  std::array<cv::Vec<double, K>, R> rows;
  std::array<double, R> values;
};

template <int K>
struct RobustFit {
  bool solved = false;
  cv::Vec<double, K> unknowns;
  cv::Matx<double, K, K> covariance;  // from the scatter over the fit's degrees of freedom
  int blocks = 0;                     // blocks the fit kept
};

// Least squares with Tukey's biweight on each block's residual length, the scatter from its
// median. The covariance scales the normal equations' inverse by the scatter per reading over the
// readings less the unknowns: a fit of few blocks has found a scatter smaller than theirs.
template <int K, int R>
RobustFit<K> robustFit(const std::vector<BlockReadings<K, R>>& blocks) {
  RobustFit<K> fit;
  std::vector<double> weights(blocks.size(), 1.0), residuals(blocks.size());
  cv::Matx<double, K, K> normal;
  double axis_scatter = kAxisScatterFloor;
  for (int pass = 0; pass < kFitPasses; ++pass) {
    normal = cv::Matx<double, K, K>::zeros();
    cv::Vec<double, K> rhs = cv::Vec<double, K>::all(0.0);
    fit.blocks = 0;
    for (std::size_t i = 0; i < blocks.size(); ++i) {
      if (!(weights[i] > 0.0)) continue;
      ++fit.blocks;
      for (int k = 0; k < R; ++k) {
        normal += weights[i] * (blocks[i].rows[k] * blocks[i].rows[k].t());
        rhs += weights[i] * blocks[i].values[k] * blocks[i].rows[k];
      }
    }
    if (fit.blocks < kMinBlocks || !cv::solve(normal, rhs, fit.unknowns, cv::DECOMP_CHOLESKY)) return fit;
    for (std::size_t i = 0; i < blocks.size(); ++i) {
      double squares = 0.0;
      for (int k = 0; k < R; ++k) {
        const double off = blocks[i].values[k] - blocks[i].rows[k].dot(fit.unknowns);
        squares += off * off;
      }
      residuals[i] = std::sqrt(squares);
    }
    axis_scatter = std::max(kMadToSigma * medianOf(residuals) / std::sqrt(double(R)), kAxisScatterFloor);
    for (std::size_t i = 0; i < blocks.size(); ++i) {
      const double u = residuals[i] / (kTukeyScatters * std::sqrt(double(R)) * axis_scatter);
      weights[i] = u < 1.0 ? (1.0 - u * u) * (1.0 - u * u) : 0.0;
    }
  }
  const int readings = R * fit.blocks;
  if (readings <= K) return fit;
  fit.solved = true;
  fit.covariance = normal.inv(cv::DECOMP_CHOLESKY) * (axis_scatter * axis_scatter * readings / (readings - K));
  return fit;
}

// The motion a fit reads on top of `motion`: the turn and the zoom are its last two unknowns.
template <int K>
BlockMotion turnAndZoom(const RobustFit<K>& fit, const ImageSimilarity& motion, BlockMotion out) {
  if (!fit.solved) return out;
  out.valid = true;
  out.rotation = motion.rotation - fit.unknowns[K - 2];
  out.log_zoom = motion.log_zoom + fit.unknowns[K - 1];
  out.rotation_sigma = std::sqrt(std::max(fit.covariance(K - 2, K - 2), 0.0));
  out.log_zoom_sigma = std::sqrt(std::max(fit.covariance(K - 1, K - 1), 0.0));
  out.blocks = fit.blocks;
  return out;
}

}  // namespace

BlockMotionReader::BlockMotionReader(int image_size, FftPlanning planning)
    : size_(image_size), block_(blockSizeFor(image_size)), fft_(block_, planning) {
  cv::createHanningWindow(window_, cv::Size(block_, block_), CV_32F);
  shifts_.reserve(kBlocksPerSide * kBlocksPerSide);
}

bool BlockMotionReader::blockShift(const cv::Mat1f& older, const cv::Mat1f& newer, const cv::Matx23d& m,
                                   const cv::Rect& block, cv::Point2d& shift) {
  // The newer frame sampled (bilinear) where the similarity puts the block's pixels; `read` made
  // sure that all of them, and their right and lower neighbours, lie inside it.
  const cv::Mat1f older_view = older(block);
  cv::Mat1f older_windowed = fft_.inPlaceInput(older_spectrum_);
  cv::Mat1f newer_windowed = fft_.inPlaceInput(newer_spectrum_);
  const float du = static_cast<float>(m(0, 0)), dv = static_cast<float>(m(1, 0));
  double older_sum = 0.0, newer_sum = 0.0;
  for (int r = 0; r < block_; ++r) {
    const double y = block.y + r;
    float u = static_cast<float>(m(0, 0) * block.x + m(0, 1) * y + m(0, 2));
    float v = static_cast<float>(m(1, 0) * block.x + m(1, 1) * y + m(1, 2));
    float* out = newer_windowed[r];
    const float* a = older_view[r];
    float row_sum = 0.0f, older_row_sum = 0.0f;
    for (int c = 0; c < block_; ++c, u += du, v += dv) {
      const int x0 = static_cast<int>(u), y0 = static_cast<int>(v);
      const float fx = u - static_cast<float>(x0), fy = v - static_cast<float>(y0);
      const float* p0 = newer[y0] + x0;
      const float* p1 = newer[y0 + 1] + x0;
      const float top = p0[0] + fx * (p0[1] - p0[0]);
      const float bottom = p1[0] + fx * (p1[1] - p1[0]);
      out[c] = top + fy * (bottom - top);
      row_sum += out[c];
      older_row_sum += a[c];
    }
    newer_sum += row_sum;
    older_sum += older_row_sum;
  }
  const float older_mean = static_cast<float>(older_sum / (block_ * block_));
  const float newer_mean = static_cast<float>(newer_sum / (block_ * block_));
  for (int r = 0; r < block_; ++r) {
    const float* w = window_[r];
    const float* a = older_view[r];
    float* oa = older_windowed[r];
    float* nb = newer_windowed[r];
    for (int c = 0; c < block_; ++c) {
      oa[c] = (a[c] - older_mean) * w[c];
      nb[c] = (nb[c] - newer_mean) * w[c];
    }
  }
  fft_.forwardInPlace(older_spectrum_);
  fft_.forwardInPlace(newer_spectrum_);
  // Normalised cross power (newer times the conjugate of older: the peak lies at the newer
  // block's shift), in place of the newer block's spectrum.
  normalisedCrossPower(newer_spectrum_, older_spectrum_, newer_spectrum_);
  fft_.inverseInPlace(newer_spectrum_);
  surface_ = fft_.realView(newer_spectrum_);
  float height = surface_(0, 0);
  cv::Point at(0, 0);
  for (int r = 0; r < block_; ++r) {
    const float* row = surface_[r];
    for (int c = 0; c < block_; ++c) {
      if (row[c] > height) {
        height = row[c];
        at = {c, r};
      }
    }
  }
  // The unnormalised inverse: a perfect match peaks at block^2.
  if (!(height >= kMinBlockPeak * block_ * block_)) return false;
  const auto value = [&](int r, int c) { return surface_((r + block_) % block_, (c + block_) % block_); };
  double x = at.x + peakOffset(value(at.y, at.x - 1), value(at.y, at.x), value(at.y, at.x + 1));
  double y = at.y + peakOffset(value(at.y - 1, at.x), value(at.y, at.x), value(at.y + 1, at.x));
  if (x > block_ / 2) x -= block_;
  if (y > block_ / 2) y -= block_;
  shift = {x, y};
  return std::hypot(x, y) <= kFollowRadius;
}

BlockMotion BlockMotionReader::read(const cv::Mat1f& older, const cv::Mat1f& newer, const ImageSimilarity& motion,
                                     BlockFit fit) {
  if (older.rows != size_ || older.cols != size_ || newer.size() != older.size()) {
    throw InputError("BlockMotionReader::read: the frames are not " + std::to_string(size_) + " x " +
                     std::to_string(size_));
  }
  BlockMotion out;
  const double centre = imageCentre(size_);
  // x_newer - c = s R (x_older - c) + d, R = [cos sin; -sin cos] (similarity_refinement.h).
  const double s = std::exp(motion.log_zoom);
  const double cs = s * std::cos(motion.rotation), sn = s * std::sin(motion.rotation);
  const cv::Matx23d older_to_newer(cs, sn, centre - cs * centre - sn * centre + motion.translation.x,  //
                                   -sn, cs, centre + sn * centre - cs * centre + motion.translation.y);
  const auto inside = [&](double x, double y) {
    const double u = older_to_newer(0, 0) * x + older_to_newer(0, 1) * y + older_to_newer(0, 2);
    const double v = older_to_newer(1, 0) * x + older_to_newer(1, 1) * y + older_to_newer(1, 2);
    return u >= 0.0 && v >= 0.0 && u < size_ - 1.0 && v < size_ - 1.0;
  };
  shifts_.clear();
  for (int y0 = kEdgeMargin; y0 + block_ <= size_ - kEdgeMargin; y0 += block_) {
    for (int x0 = kEdgeMargin; x0 + block_ <= size_ - kEdgeMargin; x0 += block_) {
      const double x1 = x0 + block_ - 1.0, y1 = y0 + block_ - 1.0;
      if (!inside(x0, y0) || !inside(x1, y0) || !inside(x0, y1) || !inside(x1, y1)) continue;
      ++out.tried;
      cv::Point2d shift;
      if (!blockShift(older, newer, older_to_newer, cv::Rect(x0, y0, block_, block_), shift)) continue;
      const double half = (block_ - 1) / 2.0;
      shifts_.push_back({{x0 + half - centre, y0 + half - centre}, shift});
    }
  }
  out.blocks = static_cast<int>(shifts_.size());
  if (out.blocks < kMinBlocks) return out;
  const double length = cv::norm(motion.translation);
  const bool across_known = length >= kMinAcrossShift;
  if (fit == BlockFit::kAcrossMotion && !across_known) return out;
  const cv::Point2d across = across_known ? cv::Point2d(-motion.translation.y, motion.translation.x) / length
                                          : cv::Point2d();
  if (fit == BlockFit::kBoth || !across_known) return fitShifts(motion, nullptr, out.tried);
  if (fit == BlockFit::kAcrossMotion) return fitShifts(motion, &across, out.tried);
  const BlockMotion both = fitShifts(motion, nullptr, out.tried);
  const BlockMotion across_only = fitShifts(motion, &across, out.tried);
  if (!across_only.valid) return both;
  if (!both.valid) return across_only;
  return across_only.rotation_sigma < both.rotation_sigma ? across_only : both;
}

BlockMotion BlockMotionReader::fitShifts(const ImageSimilarity& motion, const cv::Point2d* across,
                                         int tried) const {
  // The block at p shifted by r: r = t + w J p + e p, J p = (-p_y, p_x), for the newer frame
  // sampled at the motion; its true motion is then turned by -w and zoomed by -e on top of it.
  BlockMotion out;
  out.tried = tried;
  out.blocks = static_cast<int>(shifts_.size());
  out.across_motion = across != nullptr;
  if (across == nullptr) {
    std::vector<BlockReadings<4, 2>> readings;
    readings.reserve(shifts_.size());
    for (const BlockShift& b : shifts_) {
      const cv::Point2d& p = b.position;
      readings.push_back({{cv::Vec4d(1.0, 0.0, -p.y, p.x), cv::Vec4d(0.0, 1.0, p.x, p.y)}, {b.shift.x, b.shift.y}});
    }
    return turnAndZoom(robustFit(readings), motion, out);
  }
  // n . r = t_n + w (n . J p) + e (n . p): the shift along the motion, where depth adds its own,
  // is not read.
  const cv::Point2d n = *across;
  std::vector<BlockReadings<3, 1>> readings;
  readings.reserve(shifts_.size());
  for (const BlockShift& b : shifts_) {
    const cv::Point2d& p = b.position;
    readings.push_back({{cv::Vec3d(1.0, n.y * p.x - n.x * p.y, n.dot(p))}, {n.dot(b.shift)}});
  }
  return turnAndZoom(robustFit(readings), motion, out);
}

}  // namespace oefmt
