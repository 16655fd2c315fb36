// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/phase_correlation.h"

#include <algorithm>
#include <cmath>

#include "oefmt/error.h"
#include "oefmt/fft.h"

namespace oefmt {
namespace {

constexpr float kTinyMagnitude = 1e-30f;

void requireSameShape(const cv::Mat2f& a, const cv::Mat2f& b) {
  if (a.size() != b.size() || !a.isContinuous() || !b.isContinuous()) {
    throw InputError("phase correlation: spectra of different shapes");
  }
}

int wrap(int i, int n) { return ((i % n) + n) % n; }

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

}  // namespace

void normalisedCrossPower(const cv::Mat2f& newer, const cv::Mat2f& older, cv::Mat2f& out) {
  requireSameShape(newer, older);
  out.create(newer.size());
  const Complex* p = complexData(newer);
  const Complex* q = complexData(older);
  Complex* o = complexData(out);
  const size_t count = newer.total();
  for (size_t i = 0; i < count; ++i) {
    const float re = p[i].real() * q[i].real() + p[i].imag() * q[i].imag();
    const float im = p[i].imag() * q[i].real() - p[i].real() * q[i].imag();
    const float m = std::sqrt(re * re + im * im);
    o[i] = m > kTinyMagnitude ? Complex(re / m, im / m) : Complex(0.0f, 0.0f);
  }
}

void normalisedCrossPowerBothTurns(const cv::Mat2f& newer, const cv::Mat2f& older,
                                   cv::Mat2f& out_same, cv::Mat2f& out_half_turn) {
  requireSameShape(newer, older);
  out_same.create(newer.size());
  out_half_turn.create(newer.size());
  const Complex* p = complexData(newer);
  const Complex* q = complexData(older);
  Complex* same = complexData(out_same);
  Complex* turned = complexData(out_half_turn);
  const size_t count = newer.total();
  for (size_t i = 0; i < count; ++i) {
    const float pr = p[i].real(), pi = p[i].imag(), qr = q[i].real(), qi = q[i].imag();
    // p * conj(q) and p * q have the same magnitude |p||q|.
    const float m = std::sqrt((pr * pr + pi * pi) * (qr * qr + qi * qi));
    if (m > kTinyMagnitude) {
      const float inv = 1.0f / m;
      same[i] = Complex((pr * qr + pi * qi) * inv, (pi * qr - pr * qi) * inv);
      turned[i] = Complex((pr * qr - pi * qi) * inv, (pi * qr + pr * qi) * inv);
    } else {
      same[i] = Complex(0.0f, 0.0f);
      turned[i] = Complex(0.0f, 0.0f);
    }
  }
}

void centredSurface(const cv::Mat1f& correlation, cv::Mat1f& surface) {
  const int n = correlation.rows;
  const int half = n / 2;
  const float scale = 1.0f / (static_cast<float>(n) * static_cast<float>(n));
  surface.create(n, n);
  for (int r = 0; r < n; ++r) {
    const float* in = correlation[(r + half) % n];
    float* out = surface[r];
    for (int c = 0; c < half; ++c) out[c] = in[c + half] * scale;
    for (int c = half; c < n; ++c) out[c] = in[c - half] * scale;
  }
}

SurfacePeak findPeak(const cv::Mat1f& surface, bool cyclic_cols) {
  if (surface.empty()) throw InputError("findPeak: empty surface");
  SurfacePeak peak;
  float best = -1.0f;
  for (int r = 0; r < surface.rows; ++r) {
    const float* row = surface[r];
    for (int c = 0; c < surface.cols; ++c) {
      const float v = std::fabs(row[c]);
      if (v > best) {
        best = v;
        peak.row = r;
        peak.col = c;
      }
    }
  }
  const float centre = surface(peak.row, peak.col);
  const float sign = centre < 0.0f ? -1.0f : 1.0f;
  peak.value = std::fabs(centre);
  auto at = [&](int r, int c) -> float {
    r = wrap(r, surface.rows);
    if (cyclic_cols) {
      c = wrap(c, surface.cols);
    } else if (c < 0 || c >= surface.cols) {
      return 0.0f;
    }
    return sign * surface(r, c);
  };
  peak.sub_row = peak.row + sincRatioOffset(at(peak.row - 1, peak.col), peak.value,
                                            at(peak.row + 1, peak.col));
  peak.sub_col = peak.col + sincRatioOffset(at(peak.row, peak.col - 1), peak.value,
                                            at(peak.row, peak.col + 1));
  return peak;
}

double peakToSidelobeRatio(const cv::Mat1f& surface, const SurfacePeak& peak) {
  constexpr int kExclude = 5;
  double sum = 0.0, sum_sq = 0.0;
  long count = 0;
  for (int r = 0; r < surface.rows; ++r) {
    int dr = std::abs(r - peak.row);
    dr = std::min(dr, surface.rows - dr);
    const float* row = surface[r];
    for (int c = 0; c < surface.cols; ++c) {
      int dc = std::abs(c - peak.col);
      dc = std::min(dc, surface.cols - dc);
      if (dr <= kExclude && dc <= kExclude) continue;
      const double v = std::fabs(row[c]);
      sum += v;
      sum_sq += v * v;
      ++count;
    }
  }
  if (count < 2) return 0.0;
  const double mean = sum / count;
  // A perfect match leaves (almost) no sidelobe energy: bound the ratio instead of dividing by 0.
  const double deviation = std::max(std::sqrt(std::max(sum_sq / count - mean * mean, 0.0)), 1e-6);
  return (peak.value - mean) / deviation;
}

}  // namespace oefmt
