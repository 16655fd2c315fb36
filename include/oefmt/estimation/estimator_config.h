// SPDX-License-Identifier: GPL-3.0-or-later
// Parameters of the estimator and the table that describes each of them once (key, type, unit,
// accepted values, meaning): the configuration file's reader (config_file.h), the ROS node and
// the generated doc/parameters.md read that table. No file I/O here.
#pragma once

#include <string>
#include <vector>

#include "oefmt/enum_names.h"
#include "oefmt/estimation/local_optimizer.h"
#include "oefmt/estimation/parameter_table.h"
#include "oefmt/registration/registration_config.h"

namespace oefmt {

/// Which method turns frames into motion (the paper's comparison).
enum class EstimatorMode {
  kOefmt,  ///< o-eFMT: energy vectors, three-frame window, pattern matching, local optimizer
  kEfmt,   ///< original eFMT: multi-zoom translation profiles, consecutive pairs, PMT scale chain
  kFmt,    ///< classic FMT: single peaks, consecutive pairs
};
inline constexpr EnumName<EstimatorMode> kEstimatorModeNames[] = {
    {EstimatorMode::kOefmt, "oefmt"}, {EstimatorMode::kEfmt, "efmt"}, {EstimatorMode::kFmt, "fmt"}};
inline const char* toString(EstimatorMode mode) { return enumName(kEstimatorModeNames, mode); }

/// Pattern matching of energy vectors.
struct MatchingConfig {
  int stretch_steps = 100;            ///< PMT candidates exp(m key / 1000), m = -steps..steps
  double stretch_key_12 = 16.0;       ///< candidate spacing of PMT 0-1 vs 1-2 [per mille of ln]
  double stretch_key_02 = 13.0;       ///< candidate spacing of PMT 0-1 vs 0-2 [per mille of ln]
  double stretch_init_window = 0.6;   ///< PMT factors must lie within this of the expected one
  double max_normalised_error = 0.22; ///< qualifying error, relative to the error range
  double smoothing_sigma = 1.0;       ///< Gaussian smoothing of the vectors [bins], 0 = off
  double stretch_sigma_floor = 0.002; ///< smallest PMT sigma (relative)
  double shift_range = 25.5;          ///< PMS search range [bins]
  double shift_step = 0.04;           ///< PMS resolution [bins]
  double shift_sigma_floor = 0.04;    ///< smallest PMS sigma [bins]
  double min_peak_bins = 4.0;         ///< PMT needs the 0-1 shift beyond this many T bins
  /// T bins cleared before PMT when the 0-1 shift is beyond 4x as many: the no-motion peak of a
  /// static pattern must not decide the stretch.
  int skip_bins = 5;

  void validate() const;
};

/// Layer following and failure handling of the estimator.
struct TrackingConfig {
  /// Relative difference between the correlation peak's shift and the PMT prediction beyond which
  /// the peak is taken for another depth layer (or an alias) and only its direction is used.
  double layer_gate = 0.05;
  /// Relative window around the PMT prediction where the followed layer's T peak is searched.
  double layer_search = 0.15;
  /// A followed-layer peak must reach this fraction of the translation energy maximum.
  double layer_min_fraction = 0.01;
  /// A step off steady speed is moved to a translation energy peak at the steady length when
  /// that peak reaches this fraction of the maximum (see steadyLayerStep).
  double steady_layer_min_fraction = 0.05;
  /// Consecutive frames that may fail to register before the window restarts from the newest.
  int max_failed_frames = 3;
  /// While frames fail, predict the pose with the last motion (else hold it).
  bool predict_failed_frames = true;
  /// Sigma of a predicted step relative to the step (and rotation 0.05 rad, ln zoom 0.05 added).
  double prediction_sigma = 0.5;
  /// Weak robust prior that d12 and d02 continue pair 0-1's motion (per frame interval), with this
  /// sigma relative to the predicted length (+1 px); it breaks the tie when one pair's correlation
  /// peak is an alias and its loop partner has no pattern match. 0 = off.
  double motion_prior_sigma = 0.3;
  /// Largest acceleration of the vehicle [m/s^2]. The motion so far predicts where the next
  /// pair's translation peak lies; the window around that prediction is how far the vehicle can
  /// depart from it between two frames (fx a dt^2 / d pixels, d: assumed_altitude or the known
  /// altitude if lower). A weaker peak inside the window is accepted where a peak anywhere in the
  /// image would not be, and the highest peak outside the window and off the direction of motion
  /// (a repetitive texture's alias) is not taken at full confidence.
  double max_acceleration = 10.0;
  /// Largest yaw rate of the vehicle [rad/s] (a multirotor's fastest commanded yaw, about
  /// 200 deg/s). A pair's rotation beyond it over the frames' interval is not taken, and where it
  /// allows less than a quarter turn the rotation surface's half-turn ambiguity is decided for
  /// the smaller turn: a texture that looks the same turned by half a turn (bricks, tiles, a
  /// lattice) cannot flip the heading.
  double max_yaw_rate = 3.5;
  /// Distance [m] to the nearest scene content the acceleration window allows for, scaled as the
  /// vehicle climbs; the known altitude where that is lower. Low on purpose: roofs and walls stand
  /// nearer than the ground, and the window also holds the prediction's own errors.
  double assumed_altitude = 5.0;

  void validate() const;
};

/// The registration's sigmas are peak widths; their errors are a fraction of that (measured for
/// the energy-vector registration on rendered pairs at N = 256 and 512 and on a simulated
/// multi-depth flight). These factors turn widths into 1-sigma errors before the measurements are
/// weighted against each other and propagated into the pose covariance.
struct UncertaintyConfig {
  double rotation_scale = 0.25;  ///< theta error / rotation_sigma
  double log_zoom_scale = 0.08;  ///< ln s error / log_zoom_sigma
  double shift_scale = 0.1;      ///< error along d / shift_sigma
  double direction_scale = 0.3;  ///< error across d / (shift * direction_sigma)
  /// theta error / the zoom refinement's rotation sigma (PairRegistration::refined_rotation_sigma)
  double refined_rotation_scale = 3.1;
  /// ln s error / the zoom refinement's sigma (PairRegistration::refined_log_zoom_sigma), where
  /// the zoom was refined; the slope correction not taken adds to it unscaled
  /// (PairRegistration::slope_log_zoom_sigma)
  double refined_log_zoom_scale = 1.8;

  void validate() const;
};

/// The original eFMT's multi-zoom translation.
struct EfmtConfig {
  int zoom_samples = 5;          ///< zooms sampled between the least and most significant
  double zoom_threshold = 0.2;   ///< significant: zoom energy above this fraction of its peak
  int sector_half_width = 4;     ///< direction sector: rows on each side of the best row

  void validate() const;
};

/// Every parameter of the estimator.
struct EstimatorConfig {
  EstimatorMode mode = EstimatorMode::kOefmt;
  /// Altitude of the first frame above the dominant plane [m]; 0 = unknown (poses in units of
  /// the initial altitude).
  double initial_altitude = 0.0;
  /// Focal length of the input images [px of those images] for frames that come without a
  /// calibration (cam_param.yaml, CameraInfo); 0 = unknown. The estimator does not read it: the
  /// programs make a pinhole camera of it, whose Undistorter gives working_fx.
  double camera_fx = 0.0;
  /// Focal length of the working image (registration.size) [px]: set by the program from the
  /// camera of the frames (Undistorter::workingFx), not a parameter of the file. 0 = unknown: a
  /// 53 deg field of view (fx = size) is assumed.
  double working_fx = 0.0;
  /// Run the two registrations of a frame (1-2 and 0-2) on two threads (the second core).
  bool parallel_registrations = true;
  RegistrationConfig registration;
  MatchingConfig matching;
  LocalOptimizerOptions optimizer;
  TrackingConfig tracking;
  UncertaintyConfig uncertainty;
  EfmtConfig efmt;

  /// working_fx, or the working size when it is 0.
  double effectiveFx() const { return working_fx > 0.0 ? working_fx : registration.size; }
  /// Z_0 in output units: initial_altitude, or 1 when unknown.
  double initialAltitudeOrOne() const { return initial_altitude > 0.0 ? initial_altitude : 1.0; }
  /// The registration parameters the mode runs with: the comparison modes (efmt, fmt) are the
  /// published methods, without the zoom refinement (registration.refine_zoom).
  RegistrationConfig modeRegistration() const;
  /// Throws InputError naming the first invalid field.
  void validate() const;
};

/// Every parameter of the configuration file (config/default.yaml, oefmt_offline --config, the
/// node's private parameters), bound to `config`'s fields, in the file's order. Made for a
/// default EstimatorConfig, its values are the defaults.
ParameterTable estimatorParameters(EstimatorConfig& config);

/// A section of the table ("" = the top-level keys) and its heading, in the file's order.
struct ParameterSection {
  const char* name;
  const char* title;
};
const std::vector<ParameterSection>& estimatorParameterSections();

/// For a key the configuration no longer has: what replaced it ("" for any other key).
std::string retiredParameterHint(const std::string& key);

}  // namespace oefmt
