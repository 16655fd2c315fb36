// SPDX-License-Identifier: GPL-3.0-or-later
// Phase correlation building blocks: cross-power spectrum, centred correlation surface, peak.
#pragma once

#include <limits>

#include <opencv2/core.hpp>

#include "oefmt/registration/fft.h"
#include "oefmt/registration/simd_kernel_choice.h"

namespace oefmt {

/// out = newer * conj(older) / |newer * conj(older)|, 0 where the product vanishes.
/// With P = newer, Q = older and P(x) = Q(x - t), the correlation peaks at t.
/// With half_turn, older is taken turned by 180 degrees about the centre, whose spectrum is
/// conj(older) for a real image: out = newer * older / |newer * older|.
void normalisedCrossPower(const cv::Mat2f& newer, const cv::Mat2f& older, cv::Mat2f& out,
                          bool half_turn = false, SimdKernel kernel = SimdKernel::kAuto);

/// The same cross power, modulated so that its inverse FFT (Fft2d::inverse) is directly the
/// centred surface fftshift(correlation) / N^2, where a shift t peaks at (N/2, N/2) + t:
/// fftshift and 1/N^2 are folded into the spectrum as (-1)^(fx + fy) / N^2 (no extra pass).
/// With noise powers (a spectrum's expected |.|^2 of pure noise, see noisePower), each frequency
/// is weighted by its share of signal in both spectra, max(0, 1 - noise / |.|^2) each: frequencies
/// where sensor noise dominates would otherwise count as much as the texture's and bury the peak.
void centredCrossPower(const cv::Mat2f& newer, const cv::Mat2f& older, cv::Mat2f& out,
                       bool half_turn = false, SimdKernel kernel = SimdKernel::kAuto,
                       float newer_noise = 0.0f, float older_noise = 0.0f);

/// Height of the phase-correlation peak computed from the lowest frequencies only (an M x M
/// correlation with M = small.size()): a cheap test of which of two hypotheses matches.
double lowResolutionPeak(const cv::Mat2f& newer, const cv::Mat2f& older, bool half_turn,
                         const Fft2d& small, cv::Mat2f& scratch_spectrum,
                         cv::Mat1f& scratch_surface);

/// Sums over a surface, gathered by findPeak (for the peak-to-sidelobe ratio).
struct SurfaceStats {
  double abs_sum = 0.0;     ///< sum of |v|
  double square_sum = 0.0;  ///< sum of v^2
};

/// Integer peak of |surface| with a sub-pixel refinement.
struct SurfacePeak {
  int row = 0;
  int col = 0;
  float value = 0.0f;  ///< surface value at the integer peak (phase correlation: 0..1)
  double sub_row = 0.0;
  double sub_col = 0.0;
};

/// How a surface's peak is shaped, which decides the sub-pixel refinement.
enum class PeakShape {
  /// The Dirichlet (sinc) peak of an ideal shift (translation surface): the ratio of the peak to
  /// its larger neighbour, exact there, unlike a centre of mass or a parabola.
  kDirichlet,
  /// A peak widened by resampling (the log-polar surface): both neighbours are positive, so the
  /// larger-neighbour ratio jumps by +-0.05..0.15 bins between the two sides at whole-bin
  /// offsets. Refined by the ratio where one neighbour dominates and by the three-point centre
  /// of mass (continuous there) where both are alike, weighted by their squared asymmetry, so
  /// that the estimate does not jump at whole bins (doc/method.md, Deviations from the paper).
  kBroadened,
  /// A smooth peak (the noise-weighted translation surface: the weights act as a low-pass
  /// filter): the vertex of the parabola through the logarithms of the three values, exact for a
  /// Gaussian; the sinc ratio would read a centred peak's equal neighbours as a third of a pixel.
  kGaussian,
};

/// Finds the largest |surface| value and refines it on each axis by `shape`. Rows always wrap;
/// columns wrap if cyclic_cols. With `stats`, the sums for peakToSidelobeRatio are gathered in
/// the same pass.
SurfacePeak findPeak(const cv::Mat1f& surface, bool cyclic_cols, SurfaceStats* stats = nullptr,
                     PeakShape shape = PeakShape::kDirichlet, SimdKernel kernel = SimdKernel::kAuto);

/// The largest value within +-half_rows x +-half_cols of `centre` (x = column, y = row; rows
/// wrap, columns wrap if cyclic_cols, else are clipped), refined as findPeak does. For a search
/// where the motion so far says the peak must be. With a `sigma` (columns, rows) > 0, the value
/// weighted by a Gaussian of those widths around the centre decides: of two peaks in the
/// window, the one the prediction expects unless the other is much higher (only local maxima
/// compete then). Positions within one cell of `exclude`, and values below `min_value`, are
/// skipped (a peak already taken; the noise). When nothing qualifies, the result has value 0,
/// at the centre (a clipped centre beyond the columns stands at the nearest column).
SurfacePeak findPeakInWindow(const cv::Mat1f& surface, cv::Point centre, int half_rows,
                             int half_cols, bool cyclic_cols, PeakShape shape = PeakShape::kDirichlet,
                             cv::Point2d sigma = {0.0, 0.0}, cv::Point exclude = {-10, -10},
                             float min_value = -std::numeric_limits<float>::infinity());

/// Whether surface(r, c) is at least each of its eight neighbours (rows wrap; columns wrap if
/// cyclic_cols, else a neighbour beyond the border does not count).
bool isLocalMaximum(const cv::Mat1f& surface, int r, int c, bool cyclic_cols);

/// Peak-to-sidelobe ratio: (peak - mean) / std of |surface|, excluding an 11 x 11 window at the
/// peak, from the surface's sums gathered by findPeak. About 15 for unrelated textures at
/// N = 512, hundreds for a clean registration.
double peakToSidelobeRatio(const cv::Mat1f& surface, const SurfacePeak& peak,
                           const SurfaceStats& stats);

}  // namespace oefmt
