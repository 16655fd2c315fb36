// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/registration/pattern_matching.h"

#include <algorithm>
#include <cmath>
#include <limits>


namespace oefmt {
namespace {

// Sigma reported when no minimum qualifies: wide enough that any prior or loop overrides it.
constexpr double kInvalidSigma = 1.0;
// Values below this fraction of a vector's maximum count as empty when bounding the support.
constexpr float kSupportFraction = 1e-4f;

struct Prepared {
  std::vector<float> values;  // smoothed, non-negative, finite; two zeros appended
  int n = 0;                  // length without the padding
  int argmax = 0;
  int lo = 0, end = 0;        // [lo, end): range of the significant elements
  double sum = 0.0;           // over [lo, end)
  double sum_sq = 0.0;        // over [lo, end)
};

// Gaussian smoothing (edges replicated) of v, computed only where v has significant values (the
// energy vectors are mostly empty, and smoothing the whole vector would dominate the matching).
void smoothSupport(std::vector<float>& v, int n, double sigma) {
  if (!(sigma > 0.0) || n < 2) return;
  const float top = *std::max_element(v.begin(), v.begin() + n);
  if (!(top > 0.0f)) return;
  const float threshold = top * 1e-6f;
  int lo = n, hi = -1;
  for (int j = 0; j < n; ++j) {
    if (v[j] > threshold) {
      lo = std::min(lo, j);
      hi = j;
    }
  }
  const int radius = std::max(1, static_cast<int>(std::ceil(3.0 * sigma)));
  float kernel[64];
  const int r = std::min(radius, 31);
  float norm = 0.0f;
  for (int i = -r; i <= r; ++i) {
    kernel[i + r] = static_cast<float>(std::exp(-0.5 * i * i / (sigma * sigma)));
    norm += kernel[i + r];
  }
  const int from = std::max(0, lo - r), to = std::min(n - 1, hi + r);
  std::vector<float> out(v.begin() + from, v.begin() + to + 1);
  for (int j = from; j <= to; ++j) {
    float acc = 0.0f;
    for (int i = -r; i <= r; ++i) acc += kernel[i + r] * v[std::clamp(j + i, 0, n - 1)];
    out[j - from] = acc / norm;
  }
  std::copy(out.begin(), out.end(), v.begin() + from);
}

// Smooths, clears non-finite or negative entries and measures the vector once. Elements below
// kSupportFraction of the maximum are left out of every sum: their squares are 1e-8 of the peak's.
Prepared prepare(const std::vector<float>& v, double smoothing_sigma, int skip_bins = 0) {
  Prepared p;
  p.n = static_cast<int>(v.size());
  p.values = v;
  for (float& x : p.values) {
    if (!std::isfinite(x) || x < 0.0f) x = 0.0f;
  }
  for (int j = 0; j < std::min(skip_bins, p.n); ++j) p.values[j] = 0.0f;
  smoothSupport(p.values, p.n, smoothing_sigma);
  p.values.resize(p.n + 2, 0.0f);
  const auto top = std::max_element(p.values.begin(), p.values.begin() + p.n);
  p.argmax = static_cast<int>(top - p.values.begin());
  if (!(*top > 0.0f)) return p;
  const float threshold = *top * kSupportFraction;
  p.lo = p.n;
  for (int j = 0; j < p.n; ++j) {
    if (p.values[j] > threshold) {
      p.lo = std::min(p.lo, j);
      p.end = j + 1;
    }
  }
  for (int j = p.lo; j < p.end; ++j) {
    p.sum += p.values[j];
    p.sum_sq += double(p.values[j]) * p.values[j];
  }
  return p;
}

// Error between the mean-normalised vectors s(j) = src(j / g) (g >= 1, linear interpolation) and
// fixed(j): n * sum (s / S - fixed / F)^2 with S, F their sums. Only j where s is non-zero needs a
// pass; fixed's own moments are precomputed.
double stretchedError(const Prepared& src, const Prepared& fixed, double g) {
  const int n = src.n;
  const int first = std::max(0, static_cast<int>(std::floor(g * (src.lo - 1))) + 1);
  const int last = std::min(n, static_cast<int>(std::ceil(g * src.end)));
  const double inv = 1.0 / g;
  const float* sv = src.values.data();
  const float* fv = fixed.values.data();
  double ss = 0.0, sf = 0.0, s_sum = 0.0;
  // Vectorised: the lanes' partial sums also break the sums' serial add chains (402 calls of
  // ~500 steps per frame).
#pragma omp simd reduction(+ : ss, sf, s_sum)
  for (int j = first; j < last; ++j) {
    const double x = j * inv;
    const int i = static_cast<int>(x);
    const double t = x - i;
    const double s = sv[i] + t * (sv[i + 1] - sv[i]);  // padding keeps i + 1 in range
    ss += s * s;
    sf += s * fv[j];
    s_sum += s;
  }
  if (!(s_sum > 0.0) || !(fixed.sum > 0.0)) return std::numeric_limits<double>::infinity();
  const double e = ss / (s_sum * s_sum) - 2.0 * sf / (s_sum * fixed.sum) +
                   fixed.sum_sq / (fixed.sum * fixed.sum);
  return std::max(0.0, e) * n;
}

// Stretch error of candidate f (b(j) ~ a(j / f)): a is stretched for f >= 1, b by 1/f otherwise.
double stretchError(const Prepared& a, const Prepared& b, double f) {
  return f >= 1.0 ? stretchedError(a, b, f) : stretchedError(b, a, 1.0 / f);
}

// Parabola through (-1, l), (0, c), (1, r): vertex offset in [-0.5, 0.5], its value and the
// curvature c'' (0 when the points are not convex).
struct Vertex {
  double offset = 0.0;
  double value = 0.0;
  double curvature = 0.0;
};
Vertex parabolaVertex(double l, double c, double r) {
  Vertex v;
  v.value = c;
  const double curvature = l - 2.0 * c + r;
  if (!(curvature > 0.0) || !std::isfinite(curvature)) return v;
  v.curvature = curvature;
  v.offset = std::clamp(0.5 * (l - r) / curvature, -0.5, 0.5);
  v.value = c - 0.25 * (l - r) * v.offset;
  return v;
}

// Distance from the minimum at which the error doubles (the parabola's e* + k x^2 / 2 = 2 e*),
// in units of the sample spacing; combined with the floor.
double curvatureSigma(const Vertex& v, double spacing, double floor) {
  if (!(v.curvature > 0.0)) return kInvalidSigma;
  const double width = std::sqrt(2.0 * std::max(v.value, 0.0) / v.curvature) * spacing;
  return std::hypot(width, floor);
}

// The sharpest (largest Laplacian) local minimum among `errors` whose normalised error is below
// max_normalised and for which `allowed(index)` holds; -1 if none.
template <typename Allowed>
int sharpestMinimum(const std::vector<double>& errors, double max_normalised, Allowed allowed) {
  const int count = static_cast<int>(errors.size());
  const auto [lo, hi] = std::minmax_element(errors.begin(), errors.end());
  const double range = *hi - *lo;
  int best = -1;
  double best_laplacian = -std::numeric_limits<double>::infinity();
  for (int i = 1; i + 1 < count; ++i) {
    const double e = errors[i];
    if (e > errors[i - 1] || e > errors[i + 1] || !allowed(i)) continue;
    if (range > 0.0 && (e - *lo) / range >= max_normalised) continue;
    const double laplacian = 2.0 * errors[i - 1] - 4.0 * e + 2.0 * errors[i + 1];
    if (laplacian > best_laplacian) {
      best_laplacian = laplacian;
      best = i;
    }
  }
  return best;
}

double meanOf(const std::vector<double>& v) {
  double sum = 0.0;
  for (double x : v) sum += x;
  return v.empty() ? 0.0 : sum / static_cast<double>(v.size());
}

bool usable(const std::vector<float>& a, const std::vector<float>& b) {
  return a.size() >= 8 && a.size() == b.size();
}

// Sub-bin position (parabolic refinement) of v[j], 0 < j < size - 1, when it is a local maximum
// (a plateau counts at its left end) at least `floor` high.
std::optional<double> localMaximumAt(const std::vector<float>& v, int j, double floor) {
  if (!(v[j] >= v[j - 1] && v[j] > v[j + 1]) || v[j] < floor) return std::nullopt;
  return j + parabolaVertex(-v[j - 1], -v[j], -v[j + 1]).offset;
}

}  // namespace

MatchResult matchStretch(const std::vector<float>& a_in, const std::vector<float>& b_in,
                         const StretchMatchOptions& options) {
  MatchResult result;
  result.value = options.init > 0.0 ? options.init : 1.0;
  result.sigma = kInvalidSigma;
  if (!usable(a_in, b_in) || options.steps < 1 || !(options.key > 0.0)) return result;
  const Prepared a = prepare(a_in, options.smoothing_sigma, options.skip_bins);
  const Prepared b = prepare(b_in, options.smoothing_sigma, options.skip_bins);
  if (!(a.sum > 0.0) || !(b.sum > 0.0)) return result;

  const int n = a.n;
  const double h = options.key / 1000.0;
  const int count = 2 * options.steps + 1;
  // Factors that would push a's (or b's) peak off the end cannot be judged; they take the
  // error of their nearest valid neighbour so they never look like a minimum.
  std::vector<double> errors(count, std::numeric_limits<double>::quiet_NaN());
  for (int i = 0; i < count; ++i) {
    const double f = std::exp((i - options.steps) * h);
    if (f >= n / (a.argmax + 2.0) || 1.0 / f >= n / (b.argmax + 2.0)) continue;
    errors[i] = stretchError(a, b, f);
  }
  int first_valid = -1, last_valid = -1;
  for (int i = 0; i < count; ++i) {
    if (std::isfinite(errors[i])) {
      if (first_valid < 0) first_valid = i;
      last_valid = i;
    }
  }
  if (first_valid < 0) return result;
  for (int i = 0; i < first_valid; ++i) errors[i] = errors[first_valid];
  for (int i = last_valid + 1; i < count; ++i) errors[i] = errors[last_valid];
  for (int i = first_valid; i <= last_valid; ++i) {
    if (!std::isfinite(errors[i])) errors[i] = errors[i - 1];
  }

  const auto in_window = [&](int i) {
    if (i <= first_valid || i >= last_valid) return false;
    return options.init <= 0.0 ||
           std::fabs(std::exp((i - options.steps) * h) - options.init) < options.init_window;
  };
  const int pick = sharpestMinimum(errors, options.max_normalised_error, in_window);
  const double mean_error = meanOf(errors);
  if (pick < 0) {
    // No qualifying minimum: report the prior, flagged, rather than an edge factor (REF bug).
    const int best = static_cast<int>(std::min_element(errors.begin(), errors.end()) - errors.begin());
    if (options.init <= 0.0) result.value = std::exp((best - options.steps) * h);
    result.error = errors[best];
    result.quality = mean_error > 0.0 ? 1.0 - errors[best] / mean_error : 0.0;
    return result;
  }
  // No fixed step down (REF's bias); a parabola through the neighbours refines the pick.
  const Vertex vertex = parabolaVertex(errors[pick - 1], errors[pick], errors[pick + 1]);
  result.value = std::exp((pick - options.steps + vertex.offset) * h);
  result.sigma = curvatureSigma(vertex, h, options.sigma_floor);
  result.error = vertex.value;
  result.quality = mean_error > 0.0 ? std::clamp(1.0 - vertex.value / mean_error, 0.0, 1.0) : 0.0;
  result.valid = std::isfinite(result.value) && std::isfinite(result.sigma);
  if (!result.valid) {
    result.value = options.init > 0.0 ? options.init : 1.0;
    result.sigma = kInvalidSigma;
  }
  return result;
}

MatchResult matchShift(const std::vector<float>& a_in, const std::vector<float>& b_in,
                       const ShiftMatchOptions& options) {
  MatchResult result;
  result.sigma = options.max_shift > 0.0 ? options.max_shift : kInvalidSigma;
  if (!usable(a_in, b_in) || !(options.step > 0.0) || !(options.max_shift >= 1.0)) return result;
  Prepared a = prepare(a_in, options.smoothing_sigma);
  Prepared b = prepare(b_in, options.smoothing_sigma);
  if (!(a.sum > 0.0) || !(b.sum > 0.0)) return result;
  const int n = a.n;
  // Both normalised by their means (sums over the whole vector: a cyclic shift keeps the sum).
  double a_total = 0.0, b_total = 0.0;
  for (int i = 0; i < n; ++i) {
    a_total += a.values[i];
    b_total += b.values[i];
  }
  const double a_scale = n / a_total, b_scale = n / b_total;
  // sum (b(i + shift) - a(i))^2 = A2 + B2(t) - 2 C(shift), with t the fraction of the shift:
  // A2 and B2 need no pass per candidate, C only a pass over a's significant elements.
  double a2 = 0.0, b2 = 0.0, b_neighbours = 0.0;
  for (int i = 0; i < n; ++i) {
    a2 += double(a.values[i]) * a.values[i];
    b2 += double(b.values[i]) * b.values[i];
    b_neighbours += double(b.values[i]) * b.values[(i + 1) % n];
  }
  a2 *= a_scale * a_scale;
  b2 *= b_scale * b_scale;
  b_neighbours *= b_scale * b_scale;
  std::vector<int> support;
  for (int i = a.lo; i < a.end; ++i) {
    if (a.values[i] > a.values[a.argmax] * kSupportFraction) support.push_back(i);
  }
  // b unrolled over three periods so that b(i + shift) needs no modulo for |shift| < n.
  std::vector<double> unrolled(3 * n + 1);
  for (int j = 0; j <= 3 * n; ++j) unrolled[j] = b.values[j % n] * b_scale;
  const auto error_at = [&](double shift) {
    const double fl = std::floor(shift);
    const double t = shift - fl;
    const double* lo = unrolled.data() + n + static_cast<int>(fl);
    double cross = 0.0;
    for (int i : support) cross += a.values[i] * (lo[i] + t * (lo[i + 1] - lo[i]));
    cross *= a_scale;
    const double b2_shifted = ((1.0 - t) * (1.0 - t) + t * t) * b2 + 2.0 * t * (1.0 - t) * b_neighbours;
    return std::max(0.0, a2 + b2_shifted - 2.0 * cross) / n;
  };

  // Coarse: whole bins. The ends take part only as neighbours.
  const int reach = std::min(static_cast<int>(std::floor(options.max_shift)), n / 2 - 2);
  std::vector<double> coarse(2 * reach + 3);
  for (int k = -reach - 1; k <= reach + 1; ++k) coarse[k + reach + 1] = error_at(k);
  const int pick = sharpestMinimum(coarse, options.max_normalised_error, [](int) { return true; });
  const double mean_error = meanOf(coarse);
  if (pick < 0) {
    const int best = static_cast<int>(std::min_element(coarse.begin(), coarse.end()) - coarse.begin());
    result.error = coarse[best];
    result.quality = mean_error > 0.0 ? 1.0 - coarse[best] / mean_error : 0.0;
    return result;
  }
  const int centre = pick - reach - 1;

  // Fine: +-1 bin around the pick at `step` (the linear interpolation makes the error piecewise
  // quadratic between bins, so the minimum lies within one bin of the coarse one).
  const int half = static_cast<int>(std::ceil(1.0 / options.step));
  std::vector<double> fine(2 * half + 1);
  for (int i = -half; i <= half; ++i) fine[i + half] = error_at(centre + i * options.step);
  int best = static_cast<int>(std::min_element(fine.begin(), fine.end()) - fine.begin());
  best = std::clamp(best, 1, 2 * half - 1);
  const Vertex vertex = parabolaVertex(fine[best - 1], fine[best], fine[best + 1]);
  result.value = centre + (best - half + vertex.offset) * options.step;
  result.sigma = curvatureSigma(vertex, options.step, options.sigma_floor);
  result.error = vertex.value;
  result.quality = mean_error > 0.0 ? std::clamp(1.0 - vertex.value / mean_error, 0.0, 1.0) : 0.0;
  result.valid = std::isfinite(result.value) && std::isfinite(result.sigma) &&
                 std::fabs(result.value) <= options.max_shift;
  if (!result.valid) {
    result.value = 0.0;
    result.sigma = options.max_shift;
  }
  return result;
}

std::optional<double> peakNear(const std::vector<float>& v, double bin, double tolerance,
                               double min_fraction) {
  const int n = static_cast<int>(v.size());
  if (n < 3 || !std::isfinite(bin) || !(tolerance >= 0.0)) return std::nullopt;
  const float top = *std::max_element(v.begin(), v.end());
  if (!(top > 0.0f)) return std::nullopt;
  const int lo = std::max(1, static_cast<int>(std::floor(bin - tolerance)) - 1);
  const int hi = std::min(n - 2, static_cast<int>(std::ceil(bin + tolerance)) + 1);
  std::optional<double> best;
  for (int j = lo; j <= hi; ++j) {
    const std::optional<double> position = localMaximumAt(v, j, min_fraction * top);
    if (!position || std::fabs(*position - bin) > tolerance) continue;
    if (!best || std::fabs(*position - bin) < std::fabs(*best - bin)) best = position;
  }
  return best;
}

std::vector<EnergyPeak> energyPeaks(const std::vector<float>& v, double min_fraction) {
  std::vector<EnergyPeak> peaks;
  const int n = static_cast<int>(v.size());
  if (n < 3) return peaks;
  const float top = *std::max_element(v.begin(), v.end());
  if (!(top > 0.0f)) return peaks;
  for (int j = 1; j < n - 1; ++j) {
    if (const std::optional<double> position = localMaximumAt(v, j, min_fraction * top)) {
      peaks.push_back({*position, v[j]});
    }
  }
  std::sort(peaks.begin(), peaks.end(),
            [](const EnergyPeak& a, const EnergyPeak& b) { return a.height > b.height; });
  return peaks;
}

double refinedArgmax(const std::vector<float>& v) {
  const int n = static_cast<int>(v.size());
  if (n == 0) return 0.0;
  const int top = static_cast<int>(std::max_element(v.begin(), v.end()) - v.begin());
  if (top == 0 || top == n - 1) return top;
  return top + parabolaVertex(-v[top - 1], -v[top], -v[top + 1]).offset;
}

}  // namespace oefmt
