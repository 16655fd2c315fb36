// SPDX-License-Identifier: GPL-3.0-or-later
// The visual-odometry estimator: frames in, 4-DOF poses out (o-eFMT three-frame estimator, or the
// efmt / fmt comparison methods). No file or environment access: images come in as pixels, the
// configuration as a struct. With parallel_registrations, one frame's two registrations run on a
// worker thread the estimator owns; process() still returns only when the frame is done, so
// callers see a synchronous object (one caller at a time).
#pragma once

#include <cstddef>
#include <memory>
#include <optional>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/enum_names.h"
#include "oefmt/estimation/estimator_config.h"
#include "oefmt/estimation/local_optimizer.h"
#include "oefmt/registration/pattern_matching.h"
#include "oefmt/registration/registration.h"
#include "oefmt/estimation/length_source.h"
#include "oefmt/estimation/pose.h"

namespace oefmt {

/// How the pose of a frame was obtained.
enum class TrackingState {
  kStarted,    ///< first frame (the origin): nothing to register yet
  kTracking,   ///< registered against the previous accepted frame: the pose moved by the estimate
  kPredicted,  ///< the frame could not be registered: pose extrapolated with the last motion
  kHeld,       ///< the frame could not be registered and there was no motion to extrapolate
  kRestarted,  ///< too many frames failed: the window restarts from this frame (pose predicted, or held)
};
inline constexpr EnumName<TrackingState> kTrackingStateNames[] = {
    {TrackingState::kStarted, "started"}, {TrackingState::kTracking, "tracking"},
    {TrackingState::kPredicted, "predicted"}, {TrackingState::kHeld, "held"},
    {TrackingState::kRestarted, "restarted"}};
inline const char* toString(TrackingState state) { return enumName(kTrackingStateNames, state); }

/// Everything the estimator knows after one frame: the pose, and for diagnostics the newest pair
/// (previous accepted frame "1" -> this frame "2") and, in oefmt mode, pair 0-2 and the loop.
struct Estimate {
  std::size_t frame_index = 0;  ///< 0-based count of frames pushed since construction/reset
  double stamp = 0.0;
  Pose4 pose;                   ///< see Pose4 for frame, units and covariance
  /// The part of pose.covariance this frame added: the uncertainty of its step alone (world
  /// frame, output units; over x, y, z, yaw).
  cv::Matx44d step_covariance = cv::Matx44d::zeros();
  TrackingState state = TrackingState::kStarted;
  EstimatorMode mode = EstimatorMode::kOefmt;
  /// The pose did not come from a confident registration of this frame (state is not kTracking,
  /// or the optimizer fell back to raw measurements, or the pair was only just usable).
  bool degraded = false;
  int frame_gap = 0;  ///< frame intervals between frame 1 and this frame (1 unless frames failed)
  /// What the motion so far predicted for pair 1-2 (none at the start or after a restart).
  std::optional<RegistrationPrior> prediction12;
  /// The measured step departed from the motion so far by more than the vehicle's acceleration
  /// allows: the predicted step was integrated instead (with a covariance covering both).
  bool step_implausible = false;
  /// The motion so far rested on a reading a rival peak matched as well, and this pair's highest
  /// translation peak, unrivalled, lay elsewhere: the window started over from it (the steps
  /// before followed a periodic texture's alias).
  bool alias_left = false;
  /// The measured turn deviated from the predicted one by several times what the last turns did
  /// (an outlier of the registration): the predicted turn was integrated instead.
  bool turn_predicted = false;
  /// The same for the zoom: the predicted zoom was integrated instead of an outlier.
  bool zoom_predicted = false;
  /// Which reading gave the integrated step's length (kNone when no step was integrated).
  LengthSource length_source = LengthSource::kNone;

  // Raw registrations (energy vectors included; empty vectors in fmt mode).
  PairRegistration registration12;
  PairRegistration registration02;  ///< oefmt with a full window only (else status kTextureless)
  bool has_registration02 = false;

  // Pattern matching (oefmt; pmt12 also in efmt): stretch factors lambda_T and shifts lambda_S.
  MatchResult pmt12;  ///< T01 vs T12: ~1 at constant speed
  MatchResult pmt02;  ///< T01 vs T02: ~2 at constant speed
  MatchResult pms12;  ///< S01 vs S12 [bins]: ~0 at constant climb rate
  MatchResult pms02;  ///< S01 vs S02 [bins]
  /// How the correlation peak's d entered: as a vector, or only its direction (its length was
  /// another depth layer's or an alias, by the PMT prediction).
  PairObservations::TranslationUse translation_use12 = PairObservations::TranslationUse::kVector;
  PairObservations::TranslationUse translation_use02 = PairObservations::TranslationUse::kVector;
  /// Pair 0-2's translation did not register but its rotation/zoom peak did, within the rates'
  /// gates: the loop took its rotation alone (PairRegistration::rotation_zoom_only).
  bool rotation_only02 = false;

  PairMotion measured12;  ///< pair 1-2 as measured (calibrated sigmas), before the optimizer
  PairMotion step;        ///< pair 1-2 as integrated into the pose
  LoopSolution loop;      ///< optimizer report (status kSkipped when it did not run)
  double lambda_t12 = 0.0;  ///< |d12| / |d01| of the integrated motion
  double lambda_t02 = 0.0;  ///< |d02| / |d01| of the optimized 0-2 (0 without a loop)
  /// How far [px] the other readings of the step's length (the PMT stretch, the highest
  /// correlation peak) lay from the integrated one, where they disagreed by more than a layer's
  /// noise within the acceleration window (detail::lengthSpread); added to the pose's covariance
  /// along the step. 0 when they agree.
  double length_spread = 0.0;
  /// The length the layers in view vouched for where the step's own broke their ratios and was
  /// replaced by it, or where pair 1-2 was too weak to register on its own and was tracked on it
  /// (degraded) [px]; 0 = the step's own length stood.
  double vouched_length = 0.0;
  /// Levelled frames (setLevelled), oefmt mode: the tilt of the ground plane left in the level
  /// view [rad, the frame's image axes: x right, y down], as the pairs' stretch read it, for
  /// which this frame's refined zooms were corrected: the attitude source's error, seen from the
  /// images. Zero otherwise, and until enough pairs were read.
  cv::Point2d plane_tilt;

  double registration_ms = 0.0;  ///< spectra and registrations (efmt: with the multi-zoom profiles)
  double matching_ms = 0.0;      ///< pattern matching (part of estimator_ms)
  double optimizer_ms = 0.0;     ///< local optimizer (part of estimator_ms)
  double estimator_ms = 0.0;     ///< everything but registration: matching, optimizer, bookkeeping
  double total_ms = 0.0;

  /// Correlation surfaces of pair 1-2, only when setKeepSurfaces(true) (for debug images).
  std::optional<RegistrationSurfaces> surfaces12;
};

/// Frames in, poses out. Keeps a window of the last two accepted frames' spectra (computed once per
/// frame and reused by every pair), the motion of the last pair and its energy vectors.
///
/// oefmt (per frame, once two frames are in): reg(1->2) and reg(0->2); PMT of T01 against T12 and
/// T02 (stretch ~ lambda) and PMS of S01 against S12 and S02 (log-zoom shift); the correlation
/// peak's length is gated against the PMT prediction (another depth layer or an alias keeps only
/// its direction, and the followed layer's T peak is used instead); the LocalOptimizer closes the
/// loop 0-1, 1-2, 0-2; the optimized 1-2 is integrated and becomes the next 0-1.
/// efmt: multi-zoom translation profiles of consecutive pairs; the first pair's profile peak sets
/// the scale, later lengths follow by PMT. fmt: classic single-peak registration of consecutive
/// pairs.
///
/// Failure is a value: a frame that cannot be registered gets a predicted (or held) pose with a
/// grown covariance and state kPredicted/kHeld; after tracking.max_failed_frames such frames the
/// window restarts from the newest frame (kRestarted). Only unusable input throws.
class Estimator {
 public:
  /// Throws InputError if the configuration is invalid.
  explicit Estimator(const EstimatorConfig& config);
  /// The same, sharing an existing context (its FFT plans and tables) so that frames can be
  /// analysed ahead on another thread (see push(FrameSpectra, double)). Throws InputError if the
  /// context was made for other registration parameters than config.registration.
  Estimator(const EstimatorConfig& config, std::shared_ptr<const SpectralContext> context);
  ~Estimator();
  Estimator(const Estimator&) = delete;
  Estimator& operator=(const Estimator&) = delete;

  /// Processes one camera image of any size and supported type (see prepareImage). Returns
  /// nullopt, changing nothing, if the stamp is not finite or earlier than the previous frame's.
  /// Throws InputError for an empty image or an unsupported pixel type.
  std::optional<Estimate> push(const cv::Mat& image, double stamp,
                               ChannelOrder order = ChannelOrder::kBgr);
  /// The same for an already prepared registration.size x registration.size image.
  std::optional<Estimate> push(const PreparedImage& image, double stamp);
  /// The same for a frame already analysed by a SpectraBuilder on spectralContext(), e.g. on a
  /// reader thread while this one registers the previous frame. Throws InputError if the
  /// spectra are empty or of another size.
  std::optional<Estimate> push(FrameSpectra spectra, double stamp);
  /// The per-size tables and FFT plans frames are analysed with; shareable between threads.
  std::shared_ptr<const SpectralContext> spectralContext() const;

  /// Forgets every frame; the next frame is the new origin.
  void reset();

  /// An altitude measurement for the latest frame (a rangefinder's, above the reference plane, in
  /// output units) with its standard deviation: the pose's z, and so the scale of every later
  /// step, moves toward it (see PoseIntegrator::correctAltitude). `drift_variance` is added to
  /// z's variance first: what the images' zoom cannot see of the altitude's change since the last
  /// measurement (a camera tilted by an unknown angle reads part of its horizontal motion as
  /// climb or descent).
  void observeAltitude(double altitude, double sigma, double drift_variance = 0.0);
  /// Everything so far at another scale (PoseIntegrator::rescale): for a scale found after the
  /// first frames (a rangefinder's vote), as if the flight had started at factor times the
  /// initial altitude.
  void rescale(double factor);
  /// The altitude above the reference plane now (output units).
  double altitude() const;
  /// centreDepthRatio() (range_gate.h) of the pair the last tracked frame closed, at `beam` [px
  /// from the frame's centre]: which depth layer lies below a rangefinder. Nothing before a pair
  /// or when it cannot be told.
  std::optional<double> centreDepthRatio(cv::Point2d beam = {0.0, 0.0}) const;

  /// The camera's turn about the vertical from the previous frame to the next one pushed, as a
  /// gyro measured it [rad, counter-clockwise seen from above], and its standard deviation: in
  /// the oefmt mode, once the motion so far predicts the pairs, it stands for the predicted
  /// rotation of pair 1-2 (and of 0-2 with pair 0-1's), which is searched within its window.
  /// For the next push only.
  void setTurn(double turn, double sigma);

  /// The next pushed frame was levelled by an attitude source (a virtual nadir view,
  /// oefmt/io/nadir_view.h). In the oefmt mode the ground plane's tilt that the source's error
  /// leaves in such views is then estimated from the pairs' stretch and taken out of their zooms
  /// (oefmt/registration/plane_tilt.h): a levelled view off by an angle d [rad] reads a flight
  /// of L metres at altitude h as a change of altitude by a fraction 1.5 d L / h (0.3 degrees
  /// over 25 altitudes: 20 %). Frames not levelled are taken as a level camera's. For the next
  /// push only.
  void setLevelled() { levelled_ = true; }

  /// Copy pair 1-2's correlation surfaces into every Estimate (costs copies; for debug views).
  void setKeepSurfaces(bool keep) { keep_surfaces_ = keep; }

  const EstimatorConfig& config() const { return config_; }
  const Pose4& pose() const;
  std::size_t frameCount() const { return frame_count_; }
  /// Pixels of shift per translation-energy bin and ln(zoom) per zoom-energy bin.
  double shiftPerBin() const;
  double logZoomPerBin() const;

 private:
  struct State;
  // Finite and not earlier than the previous frame's (a frame that is not changes nothing).
  bool acceptsStamp(double stamp) const;
  std::optional<Estimate> process(FrameSpectra spectra, double stamp, double prepare_ms);

  EstimatorConfig config_;
  std::size_t frame_count_ = 0;
  bool keep_surfaces_ = false;
  std::optional<std::pair<double, double>> turn_;  // setTurn's, for the next push
  bool levelled_ = false;                          // setLevelled's, for the next push
  std::unique_ptr<State> state_;
};

}  // namespace oefmt
