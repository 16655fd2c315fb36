// SPDX-License-Identifier: GPL-3.0-or-later
// Phase correlation building blocks: cross-power spectrum, centred correlation surface, peak.
#pragma once

#include <opencv2/core.hpp>

namespace oefmt {

/// out = newer * conj(older) / |newer * conj(older)|, 0 where the product vanishes.
/// With P = newer, Q = older and P(x) = Q(x - t), the correlation peaks at t.
void normalisedCrossPower(const cv::Mat2f& newer, const cv::Mat2f& older, cv::Mat2f& out);

/// The cross powers of newer against older and against older turned by 180 degrees about the
/// centre (whose spectrum is conj(older) for a real image): one pass over the spectra.
void normalisedCrossPowerBothTurns(const cv::Mat2f& newer, const cv::Mat2f& older,
                                   cv::Mat2f& out_same, cv::Mat2f& out_half_turn);

/// surface = fftshift(correlation) / N^2: a shift t peaks at (N/2, N/2) + t. Signed values.
void centredSurface(const cv::Mat1f& correlation, cv::Mat1f& surface);

/// Integer peak of |surface| with a sub-pixel refinement.
struct SurfacePeak {
  int row = 0;
  int col = 0;
  float value = 0.0f;  ///< surface value at the integer peak (phase correlation: 0..1)
  double sub_row = 0.0;
  double sub_col = 0.0;
};

/// Finds the largest |surface| value. The sub-pixel position comes from the ratio of the peak to
/// its larger neighbour on each axis, exact for the Dirichlet (sinc) peak of an ideal shift and
/// unbiased, unlike a centre of mass or a parabola. Rows always wrap; columns wrap if cyclic_cols.
SurfacePeak findPeak(const cv::Mat1f& surface, bool cyclic_cols);

/// Peak-to-sidelobe ratio: (peak - mean) / std of |surface|, excluding an 11 x 11 window at the
/// peak. About 5 for unrelated images at N = 512, tens for a clean registration.
double peakToSidelobeRatio(const cv::Mat1f& surface, const SurfacePeak& peak);

}  // namespace oefmt
