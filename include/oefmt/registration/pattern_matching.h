// SPDX-License-Identifier: GPL-3.0-or-later
// Pattern matching of energy vectors (doc/method.md, Pattern matching): a stretch factor between
// two translation energy vectors (PMT) and a bin shift between two zoom energy vectors (PMS).
#pragma once

#include <optional>
#include <vector>

namespace oefmt {

/// Result of a pattern match. `value` is always finite; when `valid` is false it holds the
/// caller's prior (or the best unqualified candidate) and `sigma` is large.
struct MatchResult {
  double value = 0.0;   ///< stretch factor (PM) or shift in bins (PMS)
  double sigma = 0.0;   ///< 1-sigma of value: relative (of ln f) for PM, bins for PMS; finite, > 0
  bool valid = false;   ///< a well-defined, low-error minimum was found
  double error = 0.0;   ///< matching error at the selected candidate (mean-normalised vectors)
  double quality = 0.0; ///< 1 - error / mean error over the candidates (0 = no contrast, 1 = perfect)
};

/// Options of the stretch matcher PM(a, b; init, key).
struct StretchMatchOptions {
  int steps = 100;                    ///< candidates f_m = exp(m key / 1000), m = -steps..steps
  double key = 16.0;                  ///< candidate spacing in per-mille of ln f
  double init = 1.0;                  ///< expected factor; <= 0 searches every candidate
  double init_window = 0.6;           ///< only factors with |f - init| < init_window qualify
  double max_normalised_error = 0.22; ///< (e - e_min) / (e_max - e_min) must stay below this
  double smoothing_sigma = 1.0;       ///< Gaussian smoothing of both vectors first [bins], 0 = off
  double sigma_floor = 0.002;         ///< smallest reported sigma (of ln f)
  /// Bins below this are cleared in both vectors first: the no-motion peak (a static pattern
  /// correlating at zero shift) must not decide the stretch.
  int skip_bins = 0;
};

/// Stretch factor f with b(j) ~ a(j / f): a motion f times as long stretches the translation
/// energy vector by f. Candidates are compared after normalising both vectors by their means
/// (the longer-stretched one linearly interpolated); the pick is the sharpest qualifying local
/// minimum of the error (largest discrete Laplacian), refined by a parabola through its
/// neighbours. sigma comes from the curvature of the error at the minimum.
MatchResult matchStretch(const std::vector<float>& a, const std::vector<float>& b,
                         const StretchMatchOptions& options);

/// Options of the shift matcher PMS(a, b).
struct ShiftMatchOptions {
  double max_shift = 25.5;            ///< search range [-max_shift, max_shift] bins
  double step = 0.04;                 ///< resolution of the fine search [bins]
  double max_normalised_error = 0.22; ///< as for the stretch matcher
  double smoothing_sigma = 1.0;       ///< Gaussian smoothing of both vectors first [bins], 0 = off
  double sigma_floor = 0.04;          ///< smallest reported sigma [bins]
};

/// Shift lambda with b(i + lambda) ~ a(i) (cyclic vectors, linear interpolation): the zoom energy
/// vector of a pair whose log-zoom differs by -lambda ln(b) from a's. Coarse search on whole bins,
/// then a fine search at `step` around the best bin and a parabolic refinement.
MatchResult matchShift(const std::vector<float>& a, const std::vector<float>& b,
                       const ShiftMatchOptions& options);

/// Sub-bin position of the local maximum of v nearest to `bin` within +-tolerance whose height is
/// at least min_fraction of v's maximum (parabolic refinement). Used to follow one depth layer in
/// a translation energy vector.
std::optional<double> peakNear(const std::vector<float>& v, double bin, double tolerance,
                               double min_fraction);

/// A local maximum of an energy vector: sub-bin position and height.
struct EnergyPeak {
  double bin = 0.0;
  float height = 0.0f;
};

/// The local maxima of v (ends excluded) at least min_fraction of its maximum high, highest
/// first, at sub-bin positions (parabolic refinement): the depth layers of a translation energy
/// vector.
std::vector<EnergyPeak> energyPeaks(const std::vector<float>& v, double min_fraction);

/// Sub-bin position of the global maximum of v (parabolic refinement; ends are not wrapped).
double refinedArgmax(const std::vector<float>& v);

}  // namespace oefmt
