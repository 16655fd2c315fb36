// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/estimation/estimator_config.h"

#include <cmath>

#include "oefmt/error.h"

namespace oefmt {

const std::vector<ParameterSection>& estimatorParameterSections() {
  static const std::vector<ParameterSection> sections = {
      {"", "Method, scale and camera"},
      {"registration", "Pair registration (spectral rotation, zoom and translation of two frames)"},
      {"matching", "Pattern matching of energy vectors (PMT: stretch of the translation energy, "
                   "PMS: shift of the zoom energy)"},
      {"optimizer", "Local optimizer (Ceres over the loop 0-1, 1-2, 0-2 of the three-frame window)"},
      {"tracking", "Depth-layer following and failure handling"},
      {"uncertainty", "Measurement uncertainty (errors as fractions of the registration's peak widths)"},
      {"efmt", "efmt mode only: multi-zoom translation of the original eFMT"},
  };
  return sections;
}

ParameterTable estimatorParameters(EstimatorConfig& c) {
  RegistrationConfig& r = c.registration;
  MatchingConfig& m = c.matching;
  LocalOptimizerOptions& o = c.optimizer;
  TrackingConfig& t = c.tracking;
  UncertaintyConfig& u = c.uncertainty;
  EfmtConfig& e = c.efmt;
  ParameterTable table = {
      wordParameter("mode", c.mode, kEstimatorModeNames,
                    "oefmt: three-frame energy-vector estimator with pattern matching and local "
                    "optimizer; efmt: the original multi-zoom eFMT on consecutive pairs; fmt: classic "
                    "single-peak Fourier-Mellin on consecutive pairs"),
      numberParameter("initial_altitude", c.initial_altitude, "m", atLeast(0.0),
                      "altitude of the first frame above the dominant plane: the poses are in metres; "
                      "0 = unknown, the poses are in units of this altitude"),
      numberParameter("camera_fx", c.camera_fx, "px", atLeast(0.0),
                      "focal length of the input images in their pixels, for frames that come without "
                      "a calibration (cam_param.yaml, camera_info); 0 = unknown (oefmt_offline then "
                      "assumes a 53 degree field of view, the node waits for camera_info)"),
      booleanParameter("parallel_registrations", c.parallel_registrations,
                       "run the two registrations of a frame (pairs 1-2 and 0-2) on two threads; false "
                       "keeps the estimator on one core"),

      integerParameter("registration.size", r.size, "px", [] {
        ParameterRange even = atLeast(64);
        even.even = true;
        return even;
      }(), "working image size N: frames are centre-cropped to a square and resized to N x N "
           "(at most the frames' shorter side: upscaled frames register worse)"),
      numberParameter("registration.taper_fraction", r.taper_fraction, "", closedRange(0.0, 0.5),
                      "apodization taper width as a fraction of N"),
      numberParameter("registration.logpolar_radius_fraction", r.logpolar_radius_fraction, "",
                      [] {
                        ParameterRange range = closedRange(0.05, 0.75);
                        range.min_open = true;
                        return range;
                      }(),
                      "largest log-polar radius as a fraction of N; sets the log-zoom bin "
                      "ln b = ln(fraction N) / N"),
      numberParameter("registration.polar_radius_fraction", r.polar_radius_fraction, "px per bin",
                      [] {
                        ParameterRange range = closedRange(0.05, 1.0);
                        range.min_open = true;
                        return range;
                      }(),
                      "radius step of the translation polar unwrap (translation energy bin j is a "
                      "shift of j times this)"),
      integerParameter("registration.block_radius", r.block_radius, "rows", closedRange(0, 10),
                       "energy rows fused on each side of the energy peak"),
      numberParameter("registration.energy_smoothing_sigma", r.energy_smoothing_sigma, "bins",
                      closedRange(0.0, 10.0), "Gaussian smoothing of the energy vectors; 0 = off"),
      booleanParameter("registration.resolve_half_turn", r.resolve_half_turn,
                       "tell theta from theta + 180 degrees by the translation peak"),
      numberParameter("registration.min_texture", r.min_texture, "grey std (0..1)", atLeast(0.0),
                      "frames with less texture are textureless"),
      numberParameter("registration.min_confidence", r.min_confidence, "", closedRange(0.0, 1.0),
                      "registrations with a lower confidence are not used (the frame is predicted or held)"),
      integerParameter("registration.rotation_zoom_candidates", r.rotation_zoom_candidates, "",
                       closedRange(1, 10),
                       "rotation/zoom correlation peaks tried, highest first, while the registration "
                       "stays below min_confidence (pair 0-2 tries only the highest); 1 = only the highest"),
      numberParameter("registration.identity_warp_px", r.identity_warp_px, "px", closedRange(0.0, 1.0),
                      "a rotation/zoom that moves no image corner further counts as the identity: the "
                      "cached spectrum is correlated without a warp and its FFT; 0 = always warp"),
      booleanParameter("registration.noise_weighting", r.noise_weighting,
                       "weight each frequency of the translation correlation by its share of signal "
                       "(sensor noise estimated from the spectrum's outer ring)"),
      booleanParameter("registration.refine_zoom", r.refine_zoom,
                       "oefmt mode: refine each registered zoom by Gauss-Newton on the smoothed "
                       "intensities of both frames (the log-polar correlation reads a sub-bin zoom "
                       "towards the nearest bin)"),
      wordParameter("registration.fft_planning", r.fft_planning, kFftPlanningNames,
                    "FFTW planning effort, paid once per size and machine (plans are kept as FFTW "
                    "wisdom); patient plans the fastest FFTs"),

      integerParameter("matching.stretch_steps", m.stretch_steps, "", closedRange(2, 1000),
                       "PMT candidates exp(m key / 1000), m = -steps .. steps"),
      numberParameter("matching.stretch_key_12", m.stretch_key_12, "per mille of ln",
                      closedRange(1.0, 100.0), "PMT candidate spacing, pair 0-1 against pair 1-2"),
      numberParameter("matching.stretch_key_02", m.stretch_key_02, "per mille of ln",
                      closedRange(1.0, 100.0), "PMT candidate spacing, pair 0-1 against pair 0-2"),
      numberParameter("matching.stretch_init_window", m.stretch_init_window, "", closedRange(0.05, 10.0),
                      "PMT factors must lie within this of the expected one (1 for 1-2, 2 for 0-2 at "
                      "equal frame spacing)"),
      numberParameter("matching.max_normalised_error", m.max_normalised_error, "", closedRange(0.01, 1.0),
                      "a match qualifies when its error is below this fraction of the error range"),
      numberParameter("matching.smoothing_sigma", m.smoothing_sigma, "bins", closedRange(0.0, 10.0),
                      "Gaussian smoothing of both vectors before matching; 0 = off"),
      numberParameter("matching.stretch_sigma_floor", m.stretch_sigma_floor, "relative",
                      closedRange(1e-6, 1.0), "smallest PMT sigma"),
      numberParameter("matching.shift_range", m.shift_range, "bins", closedRange(1.0, 200.0),
                      "PMS search range (plus or minus)"),
      numberParameter("matching.shift_step", m.shift_step, "bins", closedRange(0.001, 0.5),
                      "PMS resolution"),
      numberParameter("matching.shift_sigma_floor", m.shift_sigma_floor, "bins", closedRange(1e-6, 10.0),
                      "smallest PMS sigma"),
      numberParameter("matching.min_peak_bins", m.min_peak_bins, "bins", closedRange(0.0, 100.0),
                      "PMT needs the previous shift beyond this many translation bins (a hovering "
                      "camera has nothing to stretch)"),
      integerParameter("matching.skip_bins", m.skip_bins, "bins", closedRange(0, 100),
                       "cleared before PMT when the previous shift is beyond 4 times as many (the "
                       "no-motion peak of static patterns must not decide the stretch)"),

      integerParameter("optimizer.max_iterations", o.max_iterations, "", closedRange(1, 1000),
                       "Levenberg-Marquardt iterations (DENSE_QR, 8 parameters)"),
      wordParameter("optimizer.robust_loss", o.robust_loss, kRobustLossNames,
                    "robust loss of each observation block (the loop blocks use huber unless none)"),
      numberParameter("optimizer.loss_scale", o.loss_scale, "sigmas", above(0.0),
                      "residual where the loss turns robust"),
      numberParameter("optimizer.loop_translation_sigma", o.loop_translation_sigma, "px", above(0.0),
                      "floor of the translation loop's sigma"),
      numberParameter("optimizer.loop_translation_sigma_relative", o.loop_translation_sigma_relative,
                      "relative", atLeast(0.0), "plus this fraction of the loop's path length"),
      numberParameter("optimizer.loop_rotation_sigma", o.loop_rotation_sigma, "rad", above(0.0),
                      "floor of the rotation loop's sigma"),
      numberParameter("optimizer.loop_log_zoom_sigma", o.loop_log_zoom_sigma, "ln zoom", above(0.0),
                      "floor of the log-zoom loop's sigma (the zoom biases of pairs with different "
                      "baselines differ by about this much)"),
      numberParameter("optimizer.function_tolerance", o.function_tolerance, "relative",
                      [] {
                        ParameterRange range = closedRange(0.0, 1.0);
                        range.min_open = range.max_open = true;
                        return range;
                      }(),
                      "cost change (and step) that counts as converged"),

      numberParameter("tracking.layer_gate", t.layer_gate, "relative", closedRange(0.001, 1.0),
                      "a correlation peak whose length differs from the PMT prediction by more belongs "
                      "to another depth layer (or is an alias): only its direction is used"),
      numberParameter("tracking.layer_search", t.layer_search, "relative", closedRange(0.001, 1.0),
                      "window around the prediction where the followed layer's translation energy "
                      "peak is searched"),
      numberParameter("tracking.layer_min_fraction", t.layer_min_fraction, "", closedRange(0.0, 1.0),
                      "a translation energy peak is a depth layer (the followed one in that window, or "
                      "the one that carries a pair too weak to register alone at the predicted "
                      "length) when it reaches this fraction of the maximum"),
      numberParameter("tracking.steady_layer_min_fraction", t.steady_layer_min_fraction, "",
                      closedRange(0.0, 1.0),
                      "a step off steady speed by more than layer_gate moves to a translation energy "
                      "peak at the steady length when that peak reaches this fraction of the maximum; "
                      "peaks this high also testify to the speed between two pairs, against a peak "
                      "taken for the followed layer; 1 = only the largest peak"),
      integerParameter("tracking.max_failed_frames", t.max_failed_frames, "frames", closedRange(0, 1000),
                       "frames in a row that may fail to register before the window restarts from "
                       "the newest"),
      booleanParameter("tracking.predict_failed_frames", t.predict_failed_frames,
                       "predict failed frames with the last motion (else hold the pose)"),
      numberParameter("tracking.prediction_sigma", t.prediction_sigma, "relative", closedRange(0.0, 100.0),
                      "sigma of a predicted step's length"),
      numberParameter("tracking.motion_prior_sigma", t.motion_prior_sigma, "relative",
                      closedRange(0.0, 100.0),
                      "sigma of the weak prior that a pair continues the previous motion (breaks ties "
                      "between an aliased correlation peak and the loop); 0 = off"),
      numberParameter("tracking.max_acceleration", t.max_acceleration, "m/s^2", closedRange(0.01, 1000.0),
                      "largest acceleration of the vehicle: how far the next translation peak may lie "
                      "from the motion so far (fx a dt^2 / d px, d = tracking.assumed_altitude or the "
                      "altitude if lower); a weaker peak inside that window is accepted, an alias "
                      "outside it is not taken at full confidence"),
      numberParameter("tracking.max_yaw_rate", t.max_yaw_rate, "rad/s", closedRange(0.01, 1000.0),
                      "largest yaw rate of the vehicle: a pair's rotation beyond it over the frames' "
                      "interval is not taken, and below a quarter turn it decides the half-turn "
                      "ambiguity of the rotation (a texture alike when turned cannot flip the heading)"),
      numberParameter("tracking.assumed_altitude", t.assumed_altitude, "m", closedRange(0.01, 1e5),
                      "distance to the nearest scene content the acceleration window allows for, "
                      "scaled as the vehicle climbs (the known altitude where that is lower): low on "
                      "purpose, as roofs and walls stand nearer than the ground and the window also "
                      "holds the prediction's own errors"),

      numberParameter("uncertainty.rotation_scale", u.rotation_scale, "", closedRange(1e-4, 100.0),
                      "rotation error per rotation peak width"),
      numberParameter("uncertainty.log_zoom_scale", u.log_zoom_scale, "", closedRange(1e-4, 100.0),
                      "log-zoom error per zoom peak width"),
      numberParameter("uncertainty.shift_scale", u.shift_scale, "", closedRange(1e-4, 100.0),
                      "translation error along the motion per shift peak width"),
      numberParameter("uncertainty.direction_scale", u.direction_scale, "", closedRange(1e-4, 100.0),
                      "translation error across the motion per (shift times direction peak width)"),
      numberParameter("uncertainty.refined_rotation_scale", u.refined_rotation_scale, "",
                      closedRange(1e-4, 100.0),
                      "rotation error per sigma of the zoom refinement's rotation (from its normal "
                      "equations); the pair's rotation weighs it against the surface's"),
      numberParameter("uncertainty.refined_log_zoom_scale", u.refined_log_zoom_scale, "",
                      closedRange(1e-4, 100.0),
                      "log-zoom error per sigma of the zoom refinement's log-zoom (from its normal "
                      "equations); with the slope correction that was not taken, the sigma of a refined zoom"),

      integerParameter("efmt.zoom_samples", e.zoom_samples, "", closedRange(1, 50),
                       "zoom hypotheses sampled between the least and the most significant zoom"),
      numberParameter("efmt.zoom_threshold", e.zoom_threshold, "", closedRange(0.0, 1.0),
                      "significant zoom energy, as a fraction of its peak"),
      integerParameter("efmt.sector_half_width", e.sector_half_width, "rows", closedRange(0, 64),
                       "half width of the direction sector (one row is 2 pi / N rad)"),
  };
  return table;
}

std::string retiredParameterHint(const std::string& key) {
  if (key == "altitude") return "renamed initial_altitude";
  if (key == "fx") {
    return "replaced by camera_fx: the focal length of the input images in their own pixels, where "
           "fx was the working image's";
  }
  return "";
}

namespace {

// Checks the rows of one section of `config` (the struct's own validate()).
void checkSection(EstimatorConfig config, const std::string& section) {
  checkParameters(estimatorParameters(config), section + ".");
}

}  // namespace

void MatchingConfig::validate() const {
  EstimatorConfig c;
  c.matching = *this;
  checkSection(c, "matching");
}

void TrackingConfig::validate() const {
  EstimatorConfig c;
  c.tracking = *this;
  checkSection(c, "tracking");
}

void UncertaintyConfig::validate() const {
  EstimatorConfig c;
  c.uncertainty = *this;
  checkSection(c, "uncertainty");
}

void EfmtConfig::validate() const {
  EstimatorConfig c;
  c.efmt = *this;
  checkSection(c, "efmt");
}

RegistrationConfig EstimatorConfig::modeRegistration() const {
  RegistrationConfig r = registration;
  r.refine_zoom = r.refine_zoom && mode == EstimatorMode::kOefmt;
  return r;
}

void EstimatorConfig::validate() const {
  EstimatorConfig copy = *this;
  checkParameters(estimatorParameters(copy));
  if (!(std::isfinite(working_fx) && working_fx >= 0.0)) {
    throw InputError("the working image's focal length must be >= 0 px (0 = unknown), got " +
                     std::to_string(working_fx));
  }
  // The registration's and the optimizer's own checks (their libraries run them too): the table
  // gives the same rules, which a test compares.
  registration.validate();
  optimizer.validate();
}

}  // namespace oefmt
