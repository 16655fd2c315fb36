// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/estimation/multi_zoom.h"

#include <algorithm>
#include <cmath>

#include "oefmt/registration/energy_vector.h"
#include "oefmt/error.h"
#include "oefmt/estimation/pair_motion.h"
#include "oefmt/registration/phase_correlation.h"
#include "oefmt/registration/warp.h"

namespace oefmt {
namespace {

int wrapIndex(int i, int n) { return ((i % n) + n) % n; }

double sampleCyclic(const std::vector<float>& v, double x) {
  const int n = static_cast<int>(v.size());
  const int i = static_cast<int>(std::floor(x));
  const double t = x - i;
  return (1.0 - t) * v[wrapIndex(i, n)] + t * v[wrapIndex(i + 1, n)];
}

// Bins around the zoom energy peak that stay above threshold * peak (cyclic, at most N/4 away).
void significantRange(const std::vector<float>& s, double threshold, int& lo, int& hi) {
  const int n = static_cast<int>(s.size());
  const int top = static_cast<int>(std::max_element(s.begin(), s.end()) - s.begin());
  const float limit = static_cast<float>(threshold) * s[top];
  lo = top;
  hi = top;
  while (top - lo < n / 4 && s[wrapIndex(lo - 1, n)] >= limit) --lo;
  while (hi - top < n / 4 && s[wrapIndex(hi + 1, n)] >= limit) ++hi;
}

}  // namespace

MultiZoomTranslator::MultiZoomTranslator(std::shared_ptr<const SpectralContext> context,
                                         const EfmtConfig& config)
    : context_(std::move(context)), config_(config) {
  if (!context_) throw InputError("MultiZoomTranslator: null context");
  config_.validate();
}

MultiZoomTranslation MultiZoomTranslator::analyse(const FrameSpectra& older, const FrameSpectra& newer,
                                                  const PairRegistration& rotation_zoom) {
  MultiZoomTranslation result;
  const int n = context_->size();
  const std::vector<float>& s = rotation_zoom.zoom_energy;
  if (static_cast<int>(s.size()) != n || older.empty() || newer.empty()) return result;
  if (!(*std::max_element(s.begin(), s.end()) > 0.0f)) return result;

  // Zoom hypotheses, uniformly between the least and the most significant zoom.
  int lo = 0, hi = 0;
  significantRange(s, config_.zoom_threshold, lo, hi);
  const int samples = (hi > lo) ? std::min(config_.zoom_samples, hi - lo + 1) : 1;
  const double log_zoom_per_bin = std::log(context_->logPolarBase());
  fused_.create(n, n);
  fused_.setTo(0.0f);
  double weight_total = 0.0;
  for (int i = 0; i < samples; ++i) {
    const double bin = samples == 1 ? 0.5 * (lo + hi) : lo + i * double(hi - lo) / (samples - 1);
    const double weight = sampleCyclic(s, bin);
    if (!(weight > 0.0)) continue;
    const double zoom = std::exp(-(bin - n / 2) * log_zoom_per_bin);
    result.zooms.push_back(zoom);
    const Fft2d& fft = context_->fft();
    cv::Mat1f warped = fft.inPlaceInput(warped_spectrum_);
    warpSimilarityWindowed(older.grey, rotation_zoom.rotation, zoom, context_->window(), warped,
                           older.mean);
    fft.forwardInPlace(warped_spectrum_);
    centredCrossPower(newer.spectrum, warped_spectrum_, cross_power_);
    fft.inverseInPlace(cross_power_);
    context_->polarRows(fft.realView(cross_power_), 0, n, polar_);
    const float w = static_cast<float>(weight);
    for (int r = 0; r < n; ++r) {
      const float* src = polar_[r];
      float* dst = fused_[r];
      for (int c = 0; c < n; ++c) {
        const float a = std::fabs(src[c]);
        dst[c] += w * a * a * a;
      }
    }
    weight_total += weight;
  }
  if (!(weight_total > 0.0)) return result;

  // The no-motion column dominates every direction once the shift is large (doc/method.md,
  // Translation).
  cv::Point peak;
  cv::minMaxLoc(fused_, nullptr, nullptr, nullptr, &peak);
  const int first_col = peak.x > 20 ? 5 : 0;
  std::vector<float> row_energy(n, 0.0f);
  for (int r = 0; r < n; ++r) {
    double acc = 0.0;
    for (int c = first_col; c < n; ++c) acc += fused_(r, c);
    row_energy[r] = static_cast<float>(acc);
  }
  const int w = config_.sector_half_width;
  int best_row = 0;
  double best_energy = -1.0;
  for (int r = 0; r < n; ++r) {
    double e = 0.0;
    for (int o = -w; o <= w; ++o) e += row_energy[wrapIndex(r + o, n)];
    if (e > best_energy) {
      best_energy = e;
      best_row = r;
    }
  }
  if (!(best_energy > 0.0)) return result;
  double moment = 0.0;
  result.profile.assign(n, 0.0f);
  for (int o = -w; o <= w; ++o) {
    const int r = wrapIndex(best_row + o, n);
    moment += o * double(row_energy[r]);
    for (int c = first_col; c < n; ++c) result.profile[c] += fused_(r, c);
  }
  const double row = best_row + moment / best_energy;
  result.direction = wrapToPi(2.0 * CV_PI * row / n);
  result.direction_sigma =
      gaussianWidth(row_energy.data(), n, row, std::max(w, 1), true) * 2.0 * CV_PI / n;
  double total = 0.0;
  for (float v : result.profile) total += v;
  for (float& v : result.profile) v = static_cast<float>(v / total);
  result.valid = true;
  return result;
}

}  // namespace oefmt
