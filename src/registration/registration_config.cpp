// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/registration/registration_config.h"

#include <cmath>
#include <string>

#include "oefmt/error.h"

namespace oefmt {
void RegistrationConfig::validate() const {
  requireParameter(size >= 64 && size % 2 == 0, "size", "must be even and >= 64, got " + std::to_string(size));
  requireParameter(taper_fraction >= 0.0 && taper_fraction <= 0.5, "taper_fraction", "must be in [0, 0.5]");
  requireParameter(logpolar_radius_fraction > 0.05 && logpolar_radius_fraction <= 0.75, "logpolar_radius_fraction",
                   "must be in (0.05, 0.75]");
  requireParameter(polar_radius_fraction > 0.05 && polar_radius_fraction <= 1.0, "polar_radius_fraction",
                   "must be in (0.05, 1]");
  requireParameter(block_radius >= 0 && block_radius <= 10, "block_radius", "must be in [0, 10]");
  requireParameter(
      std::isfinite(energy_smoothing_sigma) && energy_smoothing_sigma >= 0.0 && energy_smoothing_sigma <= 10.0,
      "energy_smoothing_sigma", "must be in [0, 10] bins");
  requireParameter(std::isfinite(min_texture) && min_texture >= 0.0, "min_texture", "must be >= 0");
  requireParameter(std::isfinite(min_confidence) && min_confidence >= 0.0 && min_confidence <= 1.0, "min_confidence",
                   "must be in [0, 1]");
  requireParameter(rotation_zoom_candidates >= 1 && rotation_zoom_candidates <= 10, "rotation_zoom_candidates",
                   "must be in [1, 10]");
  requireParameter(std::isfinite(identity_warp_px) && identity_warp_px >= 0.0 && identity_warp_px <= 1.0,
                   "identity_warp_px", "must be in [0, 1] px");
}

bool operator==(const RegistrationConfig& a, const RegistrationConfig& b) {
  return a.size == b.size && a.taper_fraction == b.taper_fraction &&
         a.logpolar_radius_fraction == b.logpolar_radius_fraction &&
         a.polar_radius_fraction == b.polar_radius_fraction && a.block_radius == b.block_radius &&
         a.energy_smoothing_sigma == b.energy_smoothing_sigma &&
         a.resolve_half_turn == b.resolve_half_turn && a.min_texture == b.min_texture &&
         a.min_confidence == b.min_confidence &&
         a.rotation_zoom_candidates == b.rotation_zoom_candidates &&
         a.identity_warp_px == b.identity_warp_px &&
         a.fft_planning == b.fft_planning && a.noise_weighting == b.noise_weighting &&
         a.refine_zoom == b.refine_zoom;
}

}  // namespace oefmt
