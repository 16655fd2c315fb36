// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/registration/phase_correlation.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "oefmt/error.h"
#include "simd_kernels.h"

namespace oefmt {
namespace {

void requireSameShape(const cv::Mat2f& a, const cv::Mat2f& b) {
  if (a.size() != b.size() || !a.isContinuous() || !b.isContinuous()) {
    throw InputError("phase correlation: spectra of different shapes");
  }
}

int wrap(int i, int n) { return ((i % n) + n) % n; }

// Normalised cross power of `count` interleaved complex values, element i multiplied by
// `factor` * (-1)^i when `alternate`; the loop has no branch and no call, so the compiler
// vectorises it (the AVX2 kernel computes the same).
void crossPowerRun(const float* p, const float* q, float* out, int count, float conjugate_sign,
                   float factor, bool alternate, SimdKernel kernel, float p_noise = 0.0f,
                   float q_noise = 0.0f) {
  const bool weighted = p_noise > 0.0f || q_noise > 0.0f;
  if (detail::runsAvx2(kernel)) {
    if (weighted) {
      detail::crossPowerRowWeightedAvx2(p, q, out, count, conjugate_sign, factor, alternate,
                                        p_noise, q_noise);
    } else {
      detail::crossPowerRowAvx2(p, q, out, count, conjugate_sign, factor, alternate);
    }
    return;
  }
  const float odd_factor = alternate ? -factor : factor;
  if (weighted) {
    for (int i = 0; i < count; ++i) {
      detail::weightedCrossPowerElement(p, q, out, i, conjugate_sign, (i & 1) ? odd_factor : factor,
                                        p_noise, q_noise);
    }
    return;
  }
#pragma omp simd
  for (int i = 0; i < count; ++i) {
    detail::crossPowerElement(p, q, out, i, conjugate_sign, (i & 1) ? odd_factor : factor);
  }
}

// Sub-sample offset of a Dirichlet (sinc) peak from the peak and its two neighbours:
// for an ideal shift d in (0, 1), C(1) / C(0) = d / (1 - d).
double sincRatioOffset(float left, float centre, float right) {
  if (centre <= 0.0f) return 0.0;
  double offset = 0.0;
  if (right >= left) {
    if (right > 0.0f) offset = right / (right + centre);
  } else if (left > 0.0f) {
    offset = -left / (left + centre);
  }
  return std::clamp(offset, -0.5, 0.5);
}

// Sub-sample offset of a peak widened by resampling. Where one neighbour dominates, the peak is
// still Dirichlet-like and the ratio is right; where both neighbours are alike (offsets near a
// whole bin), the ratio flips between the sides and the three-point centre of mass, continuous
// there, takes over. The weight is the squared asymmetry of the (positive parts of the)
// neighbours.
double widenedPeakOffset(float left, float centre, float right) {
  const double total = double(left) + centre + right;
  if (centre <= 0.0f || !(total > 0.0)) return 0.0;
  const double centre_of_mass = std::clamp((double(right) - left) / total, -0.5, 0.5);
  const double l = std::max(0.0f, left), r = std::max(0.0f, right);
  const double asymmetry = l + r > 0.0 ? (r - l) / (r + l) : 1.0;
  const double weight = asymmetry * asymmetry;
  return weight * sincRatioOffset(left, centre, right) + (1.0 - weight) * centre_of_mass;
}

// Sub-sample offset of a smooth peak: the vertex of the parabola through log(values) (a
// Gaussian's exact position); the plain parabola where a neighbour is not positive.
double gaussianPeakOffset(float left, float centre, float right) {
  if (!(centre > 0.0f)) return 0.0;
  double offset = 0.0;
  if (left > 0.0f && right > 0.0f) {
    const double l = std::log(double(left)), c = std::log(double(centre)), r = std::log(double(right));
    const double curvature = l - 2.0 * c + r;
    if (curvature < 0.0) offset = 0.5 * (l - r) / curvature;
  } else {
    const double curvature = double(left) - 2.0 * centre + right;
    if (curvature < 0.0) offset = 0.5 * (double(left) - right) / curvature;
  }
  return std::clamp(offset, -0.5, 0.5);
}

// The peak at `at` (of -surface when `negative`) refined on each axis by `shape`.
SurfacePeak refinedPeak(const cv::Mat1f& surface, cv::Point at, bool negative, bool cyclic_cols,
                        PeakShape shape) {
  SurfacePeak peak;
  peak.row = at.y;
  peak.col = at.x;
  const float sign = negative ? -1.0f : 1.0f;
  peak.value = sign * surface(at.y, at.x);
  auto sample = [&](int r, int c) -> float {
    r = wrap(r, surface.rows);
    if (cyclic_cols) {
      c = wrap(c, surface.cols);
    } else if (c < 0 || c >= surface.cols) {
      return 0.0f;
    }
    return sign * surface(r, c);
  };
  const auto offset = shape == PeakShape::kDirichlet   ? sincRatioOffset
                      : shape == PeakShape::kBroadened ? widenedPeakOffset
                                                       : gaussianPeakOffset;
  peak.sub_row = peak.row + offset(sample(peak.row - 1, peak.col), peak.value,
                                   sample(peak.row + 1, peak.col));
  peak.sub_col = peak.col + offset(sample(peak.row, peak.col - 1), peak.value,
                                   sample(peak.row, peak.col + 1));
  return peak;
}

}  // namespace

bool isLocalMaximum(const cv::Mat1f& surface, int r, int c, bool cyclic_cols) {
  const float v = surface(r, c);
  for (int dr = -1; dr <= 1; ++dr) {
    const float* row = surface[wrap(r + dr, surface.rows)];
    for (int dc = -1; dc <= 1; ++dc) {
      if (dr == 0 && dc == 0) continue;
      int cc = c + dc;
      if (cyclic_cols) {
        cc = wrap(cc, surface.cols);
      } else if (cc < 0 || cc >= surface.cols) {
        continue;
      }
      if (row[cc] > v) return false;
    }
  }
  return true;
}

void normalisedCrossPower(const cv::Mat2f& newer, const cv::Mat2f& older, cv::Mat2f& out,
                          bool half_turn, SimdKernel kernel) {
  requireSameShape(newer, older);
  out.create(newer.size());
  // older * conj -> p * conj(q); half turn: p * q (conj(conj(q))).
  crossPowerRun(newer.ptr<float>(), older.ptr<float>(), out.ptr<float>(),
                static_cast<int>(newer.total()), half_turn ? -1.0f : 1.0f, 1.0f, false, kernel);
}

void centredCrossPower(const cv::Mat2f& newer, const cv::Mat2f& older, cv::Mat2f& out,
                       bool half_turn, SimdKernel kernel, float newer_noise, float older_noise) {
  requireSameShape(newer, older);
  out.create(newer.size());
  const int n = newer.rows;
  // (-1)^(fy + fx) shifts the inverse transform by (N/2, N/2) exactly (even N); 1/N^2 undoes
  // FFTW's unnormalised inverse. Row fy and fy - N have the same parity.
  const float scale = 1.0f / (static_cast<float>(n) * static_cast<float>(n));
  for (int row = 0; row < n; ++row) {
    crossPowerRun(newer.ptr<float>(row), older.ptr<float>(row), out.ptr<float>(row), newer.cols,
                  half_turn ? -1.0f : 1.0f, (row & 1) ? -scale : scale, true, kernel, newer_noise,
                  older_noise);
  }
}

double lowResolutionPeak(const cv::Mat2f& newer, const cv::Mat2f& older, bool half_turn,
                         const Fft2d& small, cv::Mat2f& scratch_spectrum,
                         cv::Mat1f& scratch_surface) {
  requireSameShape(newer, older);
  const int n = newer.rows;
  const int m = small.size();
  scratch_spectrum.create(m, small.spectrumCols());
  for (int i = 0; i < m; ++i) {
    // Small row i holds frequency fy = i (i < m/2) or i - m; take it from big row fy mod N.
    const int fy = i < m / 2 ? i : i - m;
    const int big_row = wrap(fy, n);
    crossPowerRun(newer.ptr<float>(big_row), older.ptr<float>(big_row),
                  scratch_spectrum.ptr<float>(i), small.spectrumCols(), half_turn ? -1.0f : 1.0f,
                  1.0f, false, SimdKernel::kAuto);
  }
  small.inverse(scratch_spectrum, scratch_surface);
  // The largest |value|, from the vectorised row statistics (cv::minMaxLoc also tracked both
  // positions).
  const detail::SurfaceTotals totals = detail::surfaceTotals(
      scratch_surface[0], static_cast<int>(scratch_surface.step1()), scratch_surface.rows,
      scratch_surface.cols, detail::runsAvx2(SimdKernel::kAuto));
  return std::max(totals.max, -totals.min) / (static_cast<double>(m) * m);
}

SurfacePeak findPeak(const cv::Mat1f& surface, bool cyclic_cols, SurfaceStats* stats,
                     PeakShape shape, SimdKernel kernel) {
  if (surface.empty()) throw InputError("findPeak: empty surface");
  // One pass for the extremes and the sums: per row vectorised reductions, and the row is
  // searched for the position only when it holds a new extreme (the first, as cv::minMaxLoc).
  SurfaceStats sums;
  float min_value = surface(0, 0), max_value = surface(0, 0);
  cv::Point min_at, max_at;
  const bool avx2 = detail::runsAvx2(kernel);
  for (int r = 0; r < surface.rows; ++r) {
    const float* row = surface[r];
    const detail::RowStats row_stats = detail::rowStats(row, surface.cols, avx2);
    const float row_max = row_stats.max, row_min = row_stats.min;
    sums.abs_sum += row_stats.abs_sum;
    sums.square_sum += row_stats.square_sum;
    // (A NaN is never found: column 0 then, as the sums already carry the NaN.)
    auto column_of = [&](float value) {
      const int c = static_cast<int>(std::find(row, row + surface.cols, value) - row);
      return c < surface.cols ? c : 0;
    };
    if (row_max > max_value || r == 0) {
      max_value = row_max;
      max_at = cv::Point(column_of(row_max), r);
    }
    if (row_min < min_value || r == 0) {
      min_value = row_min;
      min_at = cv::Point(column_of(row_min), r);
    }
  }
  if (stats != nullptr) *stats = sums;
  const bool negative = -min_value > max_value;
  return refinedPeak(surface, negative ? min_at : max_at, negative, cyclic_cols, shape);
}

SurfacePeak findPeakInWindow(const cv::Mat1f& surface, cv::Point centre, int half_rows,
                             int half_cols, bool cyclic_cols, PeakShape shape, cv::Point2d sigma,
                             cv::Point exclude, float min_value) {
  if (surface.empty()) throw InputError("findPeakInWindow: empty surface");
  half_rows = std::clamp(half_rows, 0, (surface.rows - 1) / 2);
  half_cols = std::clamp(half_cols, 0, (surface.cols - 1) / 2);
  const bool weighted = sigma.x > 0.0 && sigma.y > 0.0;
  // A clipped window reports its empty result inside the surface: a centre beyond the last
  // column (a shift past a polar unwrap's reach) stands at the last column, not wrapped onto a
  // column of another radius.
  cv::Point best(cyclic_cols ? wrap(centre.x, surface.cols) : std::clamp(centre.x, 0, surface.cols - 1),
                 wrap(centre.y, surface.rows));
  double best_score = -std::numeric_limits<double>::infinity();
  // The window's columns as at most two runs of the row (a cyclic window may wrap around).
  int runs[2][2];
  int run_count = 0;
  const int first_col = centre.x - half_cols, last_col = centre.x + half_cols;
  if (cyclic_cols) {
    const int a = wrap(first_col, surface.cols);
    const int length = std::min(last_col - first_col + 1, surface.cols);
    runs[run_count][0] = a;
    runs[run_count++][1] = std::min(a + length, surface.cols);
    if (a + length > surface.cols) {
      runs[run_count][0] = 0;
      runs[run_count++][1] = a + length - surface.cols;
    }
  } else {
    runs[run_count][0] = std::max(first_col, 0);
    runs[run_count++][1] = std::min(last_col + 1, surface.cols);
  }
  for (int dr = -half_rows; dr <= half_rows; ++dr) {
    const int r = wrap(centre.y + dr, surface.rows);
    const float* row = surface[r];
    const bool excluded_row = std::min(std::abs(r - exclude.y), surface.rows - std::abs(r - exclude.y)) <= 1;
    for (int run = 0; run < run_count; ++run) {
      for (int c = runs[run][0]; c < runs[run][1]; ++c) {
        // The weight is at most 1: a value no higher than the best score cannot win.
        const float v = row[c];
        if (!(v >= min_value) || !(v > best_score)) continue;
        if (excluded_row) {  // within a cell of the excluded peak (rows and columns wrap)
          const int ec = std::abs(c - exclude.x);
          if ((cyclic_cols ? std::min(ec, surface.cols - ec) : ec) <= 1) continue;
        }
        double score = v;
        if (weighted) {
          // Only peaks compete: a weighted value on a peak's flank nearer the prediction must
          // not stand in for the peak.
          if (!(score > 0.0) || !isLocalMaximum(surface, r, c, cyclic_cols)) continue;
          const double dc = cyclic_cols ? std::remainder(c - centre.x, double(surface.cols)) : c - centre.x;
          score *= std::exp(-0.5 * (dc * dc / (sigma.x * sigma.x) + dr * dr / (sigma.y * sigma.y)));
        }
        if (score > best_score) {
          best_score = score;
          best = cv::Point(c, r);
        }
      }
    }
  }
  if (!(best_score > -std::numeric_limits<double>::infinity())) {
    SurfacePeak none;  // nothing qualified: no peak (value 0) at the centre
    none.row = best.y;
    none.col = best.x;
    none.sub_row = best.y;
    none.sub_col = best.x;
    return none;
  }
  return refinedPeak(surface, best, false, cyclic_cols, shape);
}

double peakToSidelobeRatio(const cv::Mat1f& surface, const SurfacePeak& peak,
                           const SurfaceStats& stats) {
  constexpr int kExclude = 5;
  // Whole-surface sums minus the window around the peak.
  double sum = stats.abs_sum;
  double sum_sq = stats.square_sum;
  long count = static_cast<long>(surface.total());
  for (int dr = -kExclude; dr <= kExclude; ++dr) {
    for (int dc = -kExclude; dc <= kExclude; ++dc) {
      const double v = std::fabs(surface(wrap(peak.row + dr, surface.rows),
                                         wrap(peak.col + dc, surface.cols)));
      sum -= v;
      sum_sq -= v * v;
      --count;
    }
  }
  if (count < 2) return 0.0;
  const double mean = sum / count;
  // A perfect match leaves (almost) no sidelobe energy: bound the ratio instead of dividing by 0.
  const double deviation = std::max(std::sqrt(std::max(sum_sq / count - mean * mean, 0.0)), 1e-6);
  return (peak.value - mean) / deviation;
}

}  // namespace oefmt
