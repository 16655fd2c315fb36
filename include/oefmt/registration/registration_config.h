// SPDX-License-Identifier: GPL-3.0-or-later
// Parameters of the core. Every field is documented once more in config/default.yaml and
// doc/parameters.md.
#pragma once

#include "oefmt/registration/fft.h"

namespace oefmt {

/// Parameters of the spectral pair registration (doc/method.md, Rotation and zoom; Translation).
struct RegistrationConfig {
  int size = 512;                         ///< working image size N (even, >= 64) [px]
  double taper_fraction = 0.12;           ///< apodization taper width as a fraction of N
  double logpolar_radius_fraction = 0.55; ///< largest log-polar radius as a fraction of N
  double polar_radius_fraction = 0.75;    ///< largest radius of the translation polar unwrap / N
  int block_radius = 2;                   ///< r: rows fused on each side of the energy peak
  double energy_smoothing_sigma = 1.0;    ///< Gaussian smoothing of energy vectors [bins], 0 = off
  bool resolve_half_turn = true;          ///< tell theta from theta + 180 deg by the shift peak
  double min_texture = 1e-3;              ///< grey std below which a frame counts as textureless
  double min_confidence = 0.15;           ///< results below this confidence are flagged low
  /// Rotation/zoom peaks tried, highest first, while the registration stays below
  /// min_confidence (1 = only the highest).
  int rotation_zoom_candidates = 5;
  /// A rotation/zoom that moves no pixel (the image corners) by more than this is taken as the
  /// identity: the older frame's cached spectrum is correlated without a warp and its FFT
  /// (0 = always warp) [px].
  double identity_warp_px = 0.1;
  FftPlanning fft_planning = FftPlanning::kPatient;  ///< FFTW planning effort (once per size and machine)
  /// Weight each frequency of the translation correlation by its share of signal (sensor noise
  /// estimated from the spectrum's outer ring, see noisePower).
  bool noise_weighting = true;
  /// Refine each registered zoom on the images themselves (Gauss-Newton on the intensities): the
  /// log-polar correlation reads sub-bin zooms towards the nearest bin.
  bool refine_zoom = true;

  /// Throws InputError naming the first invalid field.
  void validate() const;
};

/// Every field equal (a new field must be added to the comparison in config.cpp).
bool operator==(const RegistrationConfig& a, const RegistrationConfig& b);
inline bool operator!=(const RegistrationConfig& a, const RegistrationConfig& b) { return !(a == b); }

}  // namespace oefmt
