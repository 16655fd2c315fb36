// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/registration/energy_vector.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace oefmt {
namespace {

int wrap(int i, int n) { return ((i % n) + n) % n; }

int cyclicDistance(int a, int b, int n) {
  const int d = std::abs(a - b) % n;
  return std::min(d, n - d);
}

inline float cube(float v) {
  const float a = std::fabs(v);
  return a * a * a;
}

}  // namespace

double gaussianWidth(const float* e, int n, double centre, int radius, bool cyclic) {
  const int base = static_cast<int>(std::lround(centre));
  const double delta = centre - base;
  auto sample = [&](int i) -> double {
    if (cyclic) return e[wrap(i, n)];
    return (i < 0 || i >= n) ? 0.0 : e[i];
  };
  const double e_base = sample(base);
  double sum = 0.0;
  int terms = 0;
  for (int o = -radius; o <= radius; ++o) {
    if (o == 0) continue;
    const double e_o = sample(base + o);
    if (!(e_base > 0.0) || !(e_o > 0.0)) continue;
    const double log_ratio = std::log(e_o / e_base);
    if (log_ratio == 0.0 || !std::isfinite(log_ratio)) continue;
    const double numerator = (o - delta) * (o - delta) - delta * delta;
    const double width = std::sqrt(std::fabs(numerator / (-2.0 * log_ratio)));
    if (!std::isfinite(width)) continue;
    sum += width;
    ++terms;
  }
  if (terms == 0) return std::max(radius, 1);
  return 0.01 + sum / terms;
}

void smoothVector(std::vector<float>& v, double sigma) {
  if (!(sigma > 0.0) || v.size() < 2) return;
  const int radius = std::max(1, static_cast<int>(std::ceil(3.0 * sigma)));
  std::vector<float> kernel(2 * radius + 1);
  for (int i = -radius; i <= radius; ++i) {
    kernel[i + radius] = static_cast<float>(std::exp(-0.5 * i * i / (sigma * sigma)));
  }
  const float norm = std::accumulate(kernel.begin(), kernel.end(), 0.0f);
  const int n = static_cast<int>(v.size());
  std::vector<float> out(v.size());
  for (int j = 0; j < n; ++j) {
    float acc = 0.0f;
    for (int i = -radius; i <= radius; ++i) acc += kernel[i + radius] * v[std::clamp(j + i, 0, n - 1)];
    out[j] = acc / norm;
  }
  v.swap(out);
}

EnergyVector extractEnergyVector(const cv::Mat1f& surface, const SurfacePeak& peak,
                                 const EnergyVectorOptions& options) {
  const int rows = surface.rows;
  const int cols = surface.cols;
  // The polar surface has a bright rho ~ 0 column whenever the motion is not small.
  const int first_col = (options.suppress_low_cols && peak.sub_col > 20.0) ? 5 : 0;

  std::vector<float> row_energy(rows, 0.0f);
  double column0 = 0.0, total = 0.0;
  const bool banded = options.row_band > 0 && 2 * options.row_band + 1 < rows;
  const int band_rows = banded ? 2 * options.row_band + 1 : rows;
  for (int i = 0; i < band_rows; ++i) {
    const int r = banded ? wrap(peak.row - options.row_band + i, rows) : i;
    const float* row = surface[r];
    double acc = 0.0;
    for (int c = first_col; c < cols; ++c) acc += cube(row[c]);
    row_energy[r] = static_cast<float>(acc);
    total += acc;
    column0 += cube(row[0]);
  }

  EnergyVector result;
  int block = options.block_radius;
  int k = static_cast<int>(std::max_element(row_energy.begin(), row_energy.end()) - row_energy.begin());
  const int rounded_peak_row = wrap(static_cast<int>(std::lround(peak.sub_row)), rows);
  if (peak.col == 0 && total > 0.0 && column0 > 0.25 * total) {
    result.zero_motion = true;  // no shift: every direction row holds the same centre sample
    k = rounded_peak_row;
  } else {
    const int distance = cyclicDistance(peak.row, k, rows);
    if (distance > 10) {
      // Keep direction and shift on the same (dominant) peak rather than mixing two rows.
      result.row_conflict = true;
      k = peak.row;
    } else if (distance > 5) {
      k = rounded_peak_row;
    } else if (distance > 2) {
      block = distance;
    }
  }
  result.centre_row = k;
  result.block_radius = block;

  double weight_sum = 0.0, moment = 0.0;
  for (int o = -block; o <= block; ++o) {
    const double e = row_energy[wrap(k + o, rows)];
    weight_sum += e;
    moment += o * e;
  }
  const double mu = weight_sum > 0.0 ? moment / weight_sum : 0.0;
  double row = k + mu;
  row -= rows * std::floor(row / rows);
  result.row = row;
  result.row_sigma = gaussianWidth(row_energy.data(), rows, k + mu, block, true);

  // Fuse the block with Gaussian weights centred on mu (not the paper's reciprocal Gaussian:
  // doc/method.md, Deviations from the paper).
  std::vector<double> weights(2 * block + 1);
  double weights_total = 0.0;
  const double sigma = std::max(result.row_sigma, 1e-3);
  for (int o = -block; o <= block; ++o) {
    const double w = std::exp(-0.5 * (o - mu) * (o - mu) / (sigma * sigma));
    weights[o + block] = w;
    weights_total += w;
  }
  result.values.assign(cols, 0.0f);
  if (weights_total > 0.0) {
    for (int o = -block; o <= block; ++o) {
      const float w = static_cast<float>(weights[o + block] / weights_total);
      if (w == 0.0f) continue;
      const float* src = surface[wrap(k + o, rows)];
      for (int c = first_col; c < cols; ++c) result.values[c] += w * cube(src[c]);
    }
  }
  smoothVector(result.values, options.smoothing_sigma);
  const double energy = std::accumulate(result.values.begin(), result.values.end(), 0.0);
  if (energy > 0.0) {
    for (float& v : result.values) v = static_cast<float>(v / energy);
    const int top = static_cast<int>(std::max_element(result.values.begin(), result.values.end()) -
                                     result.values.begin());
    result.col_sigma = gaussianWidth(result.values.data(), cols, top, 2, options.cyclic_cols);
  } else {
    result.col_sigma = cols;
  }
  return result;
}

}  // namespace oefmt
