// SPDX-License-Identifier: GPL-3.0-or-later
// The original eFMT's multi-zoom translation estimate, for the `efmt` comparison mode
// (doc/method.md, Comparison modes).
#pragma once

#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/estimation/estimator_config.h"
#include "oefmt/registration/registration.h"
#include "oefmt/registration/spectra.h"

namespace oefmt {

/// A translation profile fused over several zoom hypotheses.
struct MultiZoomTranslation {
  std::vector<float> profile;  ///< radial energy along the direction, unit sum (bin j: j * step px)
  double direction = 0.0;      ///< phi [rad], image axes
  double direction_sigma = 0.0;///< [rad]
  std::vector<double> zooms;   ///< the zoom hypotheses used
  bool valid = false;          ///< the zoom energy had a peak and some surface had energy
};

/// For each of up to m zooms sampled between the least and the most significant zoom of the
/// rotation/zoom energy vector: warp the older frame by (theta, zoom), phase-correlate it with the
/// newer, unwrap in polar coordinates and take the |.|^3 energy. The surfaces are fused weighted by
/// the zoom energy; the direction is the sector (2w + 1 rows) of most energy and the profile its
/// radial energy. One instance per thread (scratch buffers).
class MultiZoomTranslator {
 public:
  MultiZoomTranslator(std::shared_ptr<const SpectralContext> context, const EfmtConfig& config);

  /// rotation_zoom: the pair's energy-vector registration (theta and its zoom energy vector).
  MultiZoomTranslation analyse(const FrameSpectra& older, const FrameSpectra& newer,
                               const PairRegistration& rotation_zoom);

 private:
  std::shared_ptr<const SpectralContext> context_;
  EfmtConfig config_;
  cv::Mat1f polar_, fused_;
  cv::Mat2f warped_spectrum_, cross_power_;  // in-place FFT buffers (images in their rows)
};

}  // namespace oefmt
