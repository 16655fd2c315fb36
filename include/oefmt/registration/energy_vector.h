// SPDX-License-Identifier: GPL-3.0-or-later
// Gaussian-fused energy-vector extraction from a correlation surface (doc/method.md,
// Energy vectors).
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/registration/phase_correlation.h"

namespace oefmt {

struct EnergyVectorOptions {
  int block_radius = 2;          ///< r: rows fused on each side of the energy row
  bool cyclic_cols = true;       ///< columns wrap (log-zoom) or not (polar radius)
  bool suppress_low_cols = false;///< zero columns 0-4 when the peak is beyond column 20 (rho ~ 0)
  double smoothing_sigma = 1.0;  ///< Gaussian smoothing of the result [bins], 0 = off
  /// Only rows within this distance of the peak row compete for the energy row (0 = all rows).
  /// Rows further than 10 away are overruled by the peak row anyway (row_conflict), so a band
  /// of 12 gives the same result for a fraction of the work.
  int row_band = 0;
};

/// The energy of a correlation surface along its columns, fused from a block of rows around the
/// row of most energy with Gaussian weights centred on the energy-weighted mean row.
struct EnergyVector {
  std::vector<float> values;  ///< one per column, normalised to unit sum (all 0 if no energy)
  int centre_row = 0;         ///< k, the row the block is centred on
  double row = 0.0;           ///< k + mu: sub-row energy centre, in [0, rows)
  double row_sigma = 0.0;     ///< Gaussian width of the row energies [rows]
  double col_sigma = 0.0;     ///< Gaussian width of `values` around its maximum [columns]
  int block_radius = 0;       ///< r actually used (widened when peak and energy rows disagree)
  bool zero_motion = false;   ///< the peak sits in column 0 with > 25 % of the energy
  bool row_conflict = false;  ///< the peak row and the energy row are > 10 rows apart
};

/// Extracts the energy vector of `surface` (signed correlation; |.|^3 is used) given its peak.
EnergyVector extractEnergyVector(const cv::Mat1f& surface, const SurfacePeak& peak,
                                 const EnergyVectorOptions& options);

/// Width of a Gaussian through samples e[centre + o], o in [-radius, radius], from pairs of samples
/// against the sample nearest the centre, + 0.01. Returns `radius` when no pair
/// is usable. `centre` is fractional; indices wrap when cyclic, else are clipped.
double gaussianWidth(const float* e, int n, double centre, int radius, bool cyclic);

/// Gaussian smoothing of a vector in place (edges replicated), sigma in bins.
void smoothVector(std::vector<float>& v, double sigma);

}  // namespace oefmt
