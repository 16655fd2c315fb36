// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/spectra.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"

namespace oefmt {
namespace {

// Separable apodization: Hann halves of length 2R at both ends, 1 inside (spec 2.2.1).
cv::Mat1f makeWindow(int n, double taper_fraction) {
  const int taper = static_cast<int>(std::floor(taper_fraction * n));
  std::vector<float> w(n, 1.0f);
  for (int i = 0; i < taper; ++i) {
    const float h = static_cast<float>(0.5 - 0.5 * std::cos(2.0 * CV_PI * i / (2.0 * taper - 1.0)));
    w[i] = h;
    w[n - 1 - i] = h;
  }
  cv::Mat1f window(n, n);
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) window(r, c) = w[r] * w[c];
  }
  return window;
}

// H = 1 - cos^2(|X|) with X sampled so that DC (N/2, N/2) is exactly 0 and the edge is pi/2.
cv::Mat1f makeHighPass(int n) {
  cv::Mat1f filter(n, n);
  for (int r = 0; r < n; ++r) {
    const double y = (r - n / 2) * CV_PI / n;
    for (int c = 0; c < n; ++c) {
      const double x = (c - n / 2) * CV_PI / n;
      const double cosine = std::cos(std::sqrt(x * x + y * y));
      filter(r, c) = static_cast<float>(1.0 - cosine * cosine);
    }
  }
  return filter;
}

}  // namespace

SpectralContext::SpectralContext(const RegistrationConfig& config)
    : config_((config.validate(), config)),
      fft_(config.size, config.fft_planning),
      window_(makeWindow(config.size, config.taper_fraction)),
      high_pass_(makeHighPass(config.size)),
      log_polar_base_(std::pow(config.logpolar_radius_fraction * config.size, 1.0 / config.size)),
      polar_radius_step_(config.polar_radius_fraction),
      small_fft_(std::min(128, config.size / 2), config.fft_planning) {
  const int n = config.size;
  const double centre = n / 2;
  const double base = log_polar_base_;
  // Rows span exactly pi (the magnitude is point-symmetric), so the row axis is cyclic. Angles
  // 0..-pi only reach the upper half plane: rows 0..N/2 (+1 for the bilinear neighbour).
  log_polar_table_ = BilinearRemapTable({n, n}, {n, n / 2 + 2}, [&](int r, int c) {
    const double angle = -CV_PI * r / n;
    const double radius = std::pow(base, c);
    return cv::Point2d(centre + radius * std::cos(angle), centre + radius * std::sin(angle));
  });
  const double step = polar_radius_step_;
  polar_table_ = BilinearRemapTable({n, n}, {n, n}, [&](int r, int c) {
    const double direction = 2.0 * CV_PI * r / n;
    const double radius = step * c;
    return cv::Point2d(centre + radius * std::cos(direction), centre + radius * std::sin(direction));
  });
}

void SpectralContext::logPolar(const cv::Mat1f& upper_half_magnitude, cv::Mat1f& out) const {
  log_polar_table_.apply(upper_half_magnitude, out);
}

void SpectralContext::polarRows(const cv::Mat1f& centred_surface, int first_row, int count,
                                cv::Mat1f& out) const {
  polar_table_.applyRows(centred_surface, first_row, count, out);
}

void upperHalfMagnitude(const cv::Mat2f& spectrum, const cv::Mat1f& filter, cv::Mat1f& magnitude) {
  const int n = spectrum.rows;
  const int half = n / 2;
  magnitude.create(half + 2, n);
  for (int row = 0; row < half + 2; ++row) {
    // Centred row `row` holds frequency fy = row - N/2; columns with fx >= 0 come from spectrum
    // row fy mod N, columns with fx < 0 from the conjugate at (-fx, -fy).
    const int fy = row - half;
    const Complex* direct = reinterpret_cast<const Complex*>(spectrum.ptr(((fy % n) + n) % n));
    const Complex* mirror = reinterpret_cast<const Complex*>(spectrum.ptr(((-fy % n) + n) % n));
    const float* h = filter[row];
    float* out = magnitude[row];
    for (int col = half; col < n; ++col) {
      const Complex v = direct[col - half];
      out[col] = std::sqrt(v.real() * v.real() + v.imag() * v.imag()) * h[col];
    }
    for (int col = 0; col < half; ++col) {
      const Complex v = mirror[half - col];
      out[col] = std::sqrt(v.real() * v.real() + v.imag() * v.imag()) * h[col];
    }
  }
}

SpectraBuilder::SpectraBuilder(std::shared_ptr<const SpectralContext> context)
    : context_(std::move(context)) {
  if (!context_) throw InputError("SpectraBuilder: null context");
}

FrameSpectra SpectraBuilder::build(const PreparedImage& image) {
  const int n = context_->size();
  if (image.grey.rows != n || image.grey.cols != n) {
    throw InputError("prepared image is " + std::to_string(image.grey.cols) + "x" +
                     std::to_string(image.grey.rows) + ", expected " + std::to_string(n) + "x" +
                     std::to_string(n));
  }
  FrameSpectra frame;
  frame.grey = image.grey.isContinuous() ? image.grey : image.grey.clone();
  frame.texture = image.texture;
  frame.invalid_pixels = image.invalid_pixels;
  cv::multiply(frame.grey, context_->window(), windowed_);
  context_->fft().forward(windowed_, frame.spectrum);
  upperHalfMagnitude(frame.spectrum, context_->highPass(), magnitude_);
  context_->logPolar(magnitude_, log_polar_);
  context_->fft().forward(log_polar_, frame.log_polar_spectrum);
  return frame;
}

FrameSpectra SpectraBuilder::build(const cv::Mat& image, ChannelOrder order) {
  return build(prepareImage(image, context_->size(), order));
}

}  // namespace oefmt
