// SPDX-License-Identifier: GPL-3.0-or-later
// Per-size tables (built once, shared read-only) and per-frame spectra (computed once per frame,
// reused by every pair the frame takes part in).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/registration/registration_config.h"
#include "oefmt/registration/fft.h"
#include "oefmt/registration/phase_correlation.h"
#include "oefmt/registration/similarity_refinement.h"
#include "oefmt/registration/image_prep.h"
#include "oefmt/registration/simd_kernel_choice.h"
#include "oefmt/registration/window.h"

namespace oefmt {

/// Everything that depends only on the configuration: FFT plans, apodization window, high-pass
/// filter and the rays of the log-polar resampling (samples are computed on the fly: a table of
/// them was 5 MB, read once per frame, slower than computing them). Immutable after
/// construction and safe to share between threads.
class SpectralContext {
 public:
  explicit SpectralContext(const RegistrationConfig& config);

  const RegistrationConfig& config() const { return config_; }
  int size() const { return config_.size; }
  const Fft2d& fft() const { return fft_; }
  /// Small FFT for the low-resolution half-turn test (size halfTurnTestSize()).
  const Fft2d& smallFft() const { return small_fft_; }
  int halfTurnTestSize() const { return small_fft_.size(); }

  const SeparableWindow& window() const { return window_; }
  /// Rows 0 .. N/2 + 1 of the centred high-pass filter: the half plane the log-polar samples.
  const cv::Mat1f& highPass() const { return high_pass_; }
  /// Log-polar radius base b: column j samples radius b^j.
  double logPolarBase() const { return log_polar_base_; }
  /// Pixels of shift per column of the translation polar unwrap.
  double polarRadiusStep() const { return polar_radius_step_; }

  /// Upper half of the centred, high-passed magnitude (see upperHalfMagnitude) -> log-polar
  /// (rows: angle 0..-pi, columns: log radius). Bilinear.
  void logPolar(const cv::Mat1f& upper_half_magnitude, cv::Mat1f& out,
                SimdKernel kernel = SimdKernel::kAuto) const;
  /// Rows first_row .. first_row + count - 1 (cyclic) of the polar unwrap of a centred
  /// correlation surface (rows: direction 2 pi row / N, columns: radius). Bilinear; the
  /// surface may be a view with padded rows.
  void polarRows(const cv::Mat1f& centred_surface, int first_row, int count, cv::Mat1f& out,
                 SimdKernel kernel = SimdKernel::kAuto) const;

 private:
  RegistrationConfig config_;
  Fft2d fft_;
  SeparableWindow window_;
  cv::Mat1f high_pass_;
  double log_polar_base_;
  double polar_radius_step_;
  Fft2d small_fft_;
  // Log-polar ray of row i: direction (cos, sin)[i]; column j samples radius radii[j].
  std::vector<float> log_polar_cos_, log_polar_sin_, log_polar_radii_;
};

/// The rotation/zoom correlation surface of a frame with an older one (Registrar's first step),
/// computed ahead by the SpectraBuilder that built both.
struct RotationZoomCorrelation {
  std::uint64_t older_serial = 0;  ///< FrameSpectra::serial of the older frame
  cv::Mat2f power;                 ///< the inverse FFT in place: realView(power) is the surface
  SurfacePeak highest;             ///< findPeak(surface, cyclic columns, broadened)
  SurfaceStats stats;              ///< of the whole surface
};

/// What the registration needs of one frame; computed once when the frame arrives.
struct FrameSpectra {
  cv::Mat1f grey;               ///< N x N prepared image (not apodized), warped when it is the older
  cv::Mat2f spectrum;           ///< FFT of the apodized grey image
  cv::Mat2f log_polar_spectrum; ///< FFT of the log-polar high-passed magnitude spectrum
  double texture = 0.0;         ///< grey standard deviation
  float mean = 0.0f;            ///< grey mean, subtracted before apodization
  int invalid_pixels = 0;       ///< non-finite input pixels that were replaced
  float noise_power = 0.0f;     ///< noisePower(spectrum) (0 without noise weighting)
  RefinementImage refinement;   ///< smoothed grey for the zoom refinement (empty without it)
  /// Unique in the process (0: none): what a RotationZoomCorrelation names its older frame by.
  std::uint64_t serial = 0;
  /// Correlations with the frames built just before this one (SpectraBuilder::correlateWithRecent).
  std::vector<RotationZoomCorrelation> correlated;

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

  /// Remember the last `frames` frames built (0: none), for correlateWithRecent.
  void setLookback(int frames);
  /// Adds to `frame` (the one built last) its rotation/zoom correlations with the remembered
  /// frames built before it, which a Registrar then takes instead of computing them: where the
  /// frames are built on a thread of their own, ahead of the registrations, that moves the
  /// correlations off the registrations' threads.
  void correlateWithRecent(FrameSpectra& frame) const;

 private:
  std::shared_ptr<const SpectralContext> context_;
  cv::Mat1f magnitude_;
  int lookback_ = 0;
  struct Remembered {
    std::uint64_t serial;
    cv::Mat2f log_polar_spectrum;  // shared, never written after build
  };
  std::vector<Remembered> recent_;  // oldest first; the last one is the frame built last
};

/// The rotation/zoom correlation of two frames' log-polar spectra: the surface (in place in
/// out.power), its highest peak and sums.
void correlateRotationZoom(const SpectralContext& context, const cv::Mat2f& newer, const cv::Mat2f& older,
                           RotationZoomCorrelation& out);

/// What to tell a user before a SpectralContext(config) measures FFT plans that the wisdom does
/// not hold yet: which plans, about how long, and where they are kept. Empty when the wisdom
/// holds them (fftPlansKnown), i.e. when making the context is quick.
std::string fftPlanningNotice(const RegistrationConfig& config);

/// Writes rows 0 .. N/2 + 1 of the centred N x N image |spectrum| * filter (DC at (N/2, N/2)):
/// the half plane the log-polar transform samples (the magnitude is point-symmetric), filling
/// the columns the real FFT omits by Hermitian symmetry. `filter` holds (at least) those rows.
void upperHalfMagnitude(const cv::Mat2f& spectrum, const cv::Mat1f& filter, cv::Mat1f& magnitude,
                        SimdKernel kernel = SimdKernel::kAuto);

/// The expected |.|^2 of a frequency of a real N x N spectrum (the real FFT's N x (N/2 + 1)
/// layout) that holds only white sensor noise: from the frequencies beyond 0.4 N of the centre,
/// where a scene's texture has the least power, as the ring's lower quartile over its value for
/// pure noise (|.|^2 of white noise is exponentially distributed: the quartile is ln(4/3) times
/// the mean). A scene with fine texture there raises it, which weights those frequencies down
/// a little; a blurred or upscaled frame gives about 0.
float noisePower(const cv::Mat2f& spectrum);

}  // namespace oefmt
