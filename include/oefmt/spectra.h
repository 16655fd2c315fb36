// SPDX-License-Identifier: GPL-3.0-or-later
// Per-size tables (built once, shared read-only) and per-frame spectra (computed once per frame,
// reused by every pair the frame takes part in).
#pragma once

#include <memory>

#include <opencv2/core.hpp>

#include "oefmt/config.h"
#include "oefmt/fft.h"
#include "oefmt/image_prep.h"

namespace oefmt {

/// Everything that depends only on the configuration: FFT plans, apodization window, high-pass
/// filter and the remap tables of the log-polar and polar resamplings. Immutable after
/// construction and safe to share between threads.
class SpectralContext {
 public:
  explicit SpectralContext(const RegistrationConfig& config);

  const RegistrationConfig& config() const { return config_; }
  int size() const { return config_.size; }
  const Fft2d& fft() const { return fft_; }

  const cv::Mat1f& window() const { return window_; }
  const cv::Mat1f& highPass() const { return high_pass_; }
  /// Log-polar radius base b: column j samples radius b^j.
  double logPolarBase() const { return log_polar_base_; }
  /// Pixels of shift per column of the translation polar unwrap.
  double polarRadiusStep() const { return polar_radius_step_; }

  /// |centred spectrum| * high-pass -> log-polar (rows: angle 0..-pi, columns: log radius).
  void logPolar(const cv::Mat1f& centred_magnitude, cv::Mat1f& out) const;
  /// Centred correlation surface -> polar (rows: direction 0..2pi, columns: radius).
  void polar(const cv::Mat1f& centred_surface, cv::Mat1f& out) const;

 private:
  RegistrationConfig config_;
  Fft2d fft_;
  cv::Mat1f window_;
  cv::Mat1f high_pass_;
  double log_polar_base_;
  double polar_radius_step_;
  cv::Mat log_polar_map1_, log_polar_map2_;
  cv::Mat polar_map1_, polar_map2_;
};

/// What the registration needs of one frame; computed once when the frame arrives.
struct FrameSpectra {
  cv::Mat1f grey;               ///< N x N prepared image (not apodized), warped when it is the older
  cv::Mat2f spectrum;           ///< FFT of the apodized grey image
  cv::Mat2f log_polar_spectrum; ///< FFT of the log-polar high-passed magnitude spectrum
  double texture = 0.0;         ///< grey standard deviation
  int invalid_pixels = 0;       ///< non-finite input pixels that were replaced

  bool empty() const { return grey.empty(); }
};

/// Computes a frame's spectra. Reuses `scratch` buffers between calls (one per thread).
class SpectraBuilder {
 public:
  explicit SpectraBuilder(std::shared_ptr<const SpectralContext> context);

  /// From an N x N prepared image.
  FrameSpectra build(const PreparedImage& image);
  /// From any camera image (converted, cropped and resized first).
  FrameSpectra build(const cv::Mat& image, ChannelOrder order = ChannelOrder::kBgr);

  const SpectralContext& context() const { return *context_; }

 private:
  std::shared_ptr<const SpectralContext> context_;
  cv::Mat1f windowed_;
  cv::Mat1f magnitude_;
  cv::Mat1f log_polar_;
};

/// Writes |spectrum| * filter into the centred N x N image `magnitude` (DC at (N/2, N/2)),
/// filling the half the real FFT omits by Hermitian symmetry.
void centredMagnitude(const cv::Mat2f& spectrum, const cv::Mat1f& filter, cv::Mat1f& magnitude);

}  // namespace oefmt
