// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/estimation/estimator.h"
#include "oefmt/estimation/layer_ratio_memory.h"
#include "oefmt/estimation/range_gate.h"

#include <algorithm>
#include <chrono>
#include <deque>
#include <cmath>
#include <exception>
#include <future>
#include <limits>
#include <string>
#include <utility>

#include "estimator_measurements.h"
#include "oefmt/error.h"
#include "oefmt/estimation/multi_zoom.h"
#include "oefmt/estimation/plane_tilt_tracker.h"
#include "worker_thread.h"

namespace oefmt {
namespace {

using Clock = std::chrono::steady_clock;
using detail::alongTrackSigma;
using detail::kMinShiftSigma;

double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Growth of a held pose per frame, relative to the altitude (x, y, z) and in rad (yaw): large on
// purpose, the camera may have moved anywhere.
constexpr double kHeldPositionSigma = 0.1;
constexpr double kHeldAltitudeSigma = 0.05;
constexpr double kHeldYawSigma = 0.1;
// Extra sigmas of a predicted step's rotation [rad] and log-zoom.
constexpr double kPredictedRotationSigma = 0.05;
constexpr double kPredictedLogZoomSigma = 0.05;

// Half width of the window where a pair's rotation/zoom peak is searched first [surface bins;
// at N = 512 one rotation bin is 0.35 deg, one zoom bin 1.1 %], plus three sigmas of the
// prediction. A yaw or climb rate that changes by more within one frame interval is still found
// by the search of the whole surface that follows.
constexpr double kPriorWindowBins = 6.0;
// Steps whose median predicts the next rotation and zoom: a yaw or climb rate that changes
// shows in the median after two steps, a single wrong step not at all.
constexpr std::size_t kPredictionSteps = 3;
// The layer ratios a step must keep (LayerRatioMemory): held in 8 of the last 12 measured steps
// to within 1 %. A layer's peak sits to a few tenths of a per cent, and a depth ratio moves with
// the altitude only: a climb of 3 % of the altitude over those steps (a steep one) moves a roof at
// 30 % of it against the ground by 1 %, after which the older steps no longer support the ratio
// (the memory falls silent rather than wrong). 8 of 12 let a layer be missing from a few pairs'
// vectors, and keep a run of a few wrong steps (a periodic texture's alias) from becoming a ratio
// that then holds the steps back from their return to the right length.
constexpr int kLayerRatioFrames = 12;
constexpr int kLayerRatioSupport = 8;
constexpr double kLayerRatioTolerance = 0.01;
// A measured turn or zoom is weighed against the one the last steps' rates predict for it
// (detail::RateDeviations): by the spread of the last 12 accepted readings' deviations from their
// predictions, once 6 of them are known. A deviation beyond 4 of those spreads is an outlier: a
// normal error lies within 4 sigmas all but once in 15 000. The spread is at least a tenth of a
// surface bin, within which the surface's interpolation itself scatters.
constexpr std::size_t kRateDeviationFrames = 12;
constexpr std::size_t kRateDeviationSupport = 6;
constexpr double kRateGateSpreads = 4.0;
constexpr double kRateDeviationFloorBins = 0.1;
// Smallest radius of the translation window [px]: sub-pixel noise and rounding.
constexpr double kTranslationWindowFloor = 2.0;

// Pair 0-2 is not registered when even its slowest depth layer is predicted to move more than
// this fraction of N along an axis: the circular correlation folds shifts beyond N/2 to the
// other side, and near it a peak cannot be told from its fold (pair 0-2 of a flight at 60 %
// overlap moves 0.7 N).
constexpr double kMaxPairShiftFraction = 0.45;

// Whether a pair's rotation and zoom lie within the prediction's window (true without one).
bool withinWindow(const PairMotion& motion, const std::optional<RegistrationPrior>& prior) {
  return !prior || prior->contains(motion.rotation, motion.log_zoom);
}

struct WindowFrame {
  FrameSpectra spectra;
  std::size_t index = 0;
  double stamp = 0.0;
};

// `step` at the length the layers vouched for: its sigma along the step the ratios' tolerance,
// across it its own, scaled with the length.
PairMotion atVouchedLength(const PairMotion& step, double vouched) {
  const double along = alongTrackSigma(step);
  const double across = std::sqrt(std::max(cv::trace(step.translation_covariance) - along * along, 0.0));
  return detail::withLength(step, vouched, std::max(kLayerRatioTolerance * vouched, detail::kMinShiftSigma),
                            std::max(across * vouched / step.shift(), detail::kMinShiftSigma));
}

}  // namespace

// The window, the previous pair and the per-size machinery; one method per stage of a frame.
struct Estimator::State {
  State(const EstimatorConfig& c, std::shared_ptr<const SpectralContext> context)
      : config(c),
        registrar(std::move(context)),
        registrar02(registrar.sharedContext()),
        optimizer(c.optimizer),
        integrator(c.initialAltitudeOrOne(), c.effectiveFx()),
        multi_zoom(registrar.sharedContext(), c.efmt) {
    // A pair 0-2 that does not register only costs this frame its loop: the further rotation/zoom
    // candidates (up to 4 more registrations, on the tail latency) are kept for pair 1-2.
    registrar02.setRotationZoomCandidates(1);
    // Pair 0-2's turn meets pairs 0-1's and 1-2's in the loop, where the blocks' reading of pair
    // 1-2 already stands: read for pair 0-2 as well, they doubled their time for little
    // (doc/method.md, Rotation and zoom).
    registrar02.setBlockReading(false);
  }

  void clear() {
    f0.reset();
    f1.reset();
    failed_frame.reset();
    turn_since_f1 = std::make_pair(0.0, 0.0);
    forgetPair01();
    failed = 0;
    anchor.reset();
    last_step.reset();
    restart_length.reset();
    forgetMotionModel();
    plane_tilt.clear();
    layer_ratios.clear();
    levelled = false;
    implausible_steps = 0;
    unconfirmed_steps = 0;
    ambiguous_motion = false;
    doubt_log_share = 0.0;
    started = false;
    last_stamp = -std::numeric_limits<double>::infinity();
  }
  // The motion model starts over from the next measurements: its steps, its rates and what it
  // knows of their deviations from its predictions.
  void forgetMotionModel() {
    recent_steps.clear();
    recent_rates.clear();
    turn_deviations.clear();
    zoom_deviations.clear();
  }
  // The window starts over from frame 1 (a restart, or an alias left): nothing of pair 0-1 or of
  // the steps before carries over, so the next registrations search everywhere (the rates, which
  // the vehicle keeps, stay).
  void startWindowOver() {
    f0.reset();
    forgetPair01();
    recent_steps.clear();
    implausible_steps = 0;
  }
  void forgetPair01() {
    have01 = false;
    layer_ratios.clear();
    translation01.clear();
    zoom01.clear();
  }

  // No anchor frame yet: the frame becomes it (the origin for the very first one).
  void anchorFrame(WindowFrame&& frame, bool textured, Estimate& est);
  // The frame could not be registered: predict or hold the pose, maybe restart the window.
  void registrationFailed(WindowFrame&& frame, bool textured, Estimate& est);
  // The frame did not register against frame 1 after a single failed frame (oefmt mode): where
  // it registers against the failed frame instead, that frame becomes frame 1 with its predicted
  // step, est's pair 1-2 and rates_rotation12 are that pair's, and pair 0-2 is dropped: true.
  bool registerAfterFailedFrame(const WindowFrame& frame, RegistrationMethod method,
                                const std::optional<std::pair<double, double>>& turn,
                                RegistrationSurfaces* surfaces, Estimate& est, double& rates_rotation12);
  // Keeps track of whether the motion since the last start rests on an ambiguous reading (a
  // rival peak as high) and, where this usable pair took the surface's unrivalled peak outside
  // the prediction's window, starts the window over from frame 1 with it: true (pair 0-2 is then
  // dropped).
  bool weighAmbiguity(Estimate& est);
  // Multi-zoom step of the efmt mode; its fused profile goes to next_translation01.
  PairMotion efmtStep(const WindowFrame& frame, Estimate& est,
                      std::vector<float>& next_translation01);
  // Three-frame step of the oefmt mode: pair 0-2, pattern matching, optimizer.
  PairMotion oefmtStep(const WindowFrame& frame, Estimate& est, bool with02);
  // Integrates the step and slides the window.
  void advance(WindowFrame&& frame, const PairMotion& step, std::vector<float>&& next_translation01,
               Estimate& est);
  cv::Matx44d heldGrowth() const;
  // The step against the motion so far: one the vehicle could not have made (further from the
  // prediction than the acceleration window) is replaced by the prediction, with a covariance
  // that covers the difference, and marked degraded; after tracking.max_failed_frames such steps
  // in a row the measurements are believed and the motion model starts over.
  PairMotion plausibleStep(const PairMotion& step, Estimate& est);
  // The step with the predicted turn (zoom) where its own turn (zoom) is an outlier of the recent
  // deviations from the predictions (at most one step in a row); the turn not where a gyro's turn
  // is off the rates' prediction (`rates_rotation`) as well.
  PairMotion consistentRates(const PairMotion& step, double rates_rotation, bool gyro_turn, Estimate& est);
  // The step at the length the layers in view vouch for (LayerRatioMemory) where its own length
  // breaks their ratios by more than tracking.layer_gate (oefmt mode).
  PairMotion vouchedStep(const PairMotion& step, Estimate& est) const;
  // Before the first pair after a restart is integrated: its scale continued (see the definition).
  void continueScale(const PairMotion& step, const Estimate& est);
  // A registration too weak to use on its own whose layers in view still vouch (by the ratios
  // they held) for the length the motion so far predicts: that step (oefmt mode), with
  // est.measured12 and est.vouched_length set.
  std::optional<PairMotion> corroboratedStep(Estimate& est) const;
  /// corroboratedStep along the predicted direction, where the chosen peak lies off it.
  std::optional<PairMotion> corroboratedAlongPrediction(const WindowFrame& frame, Estimate& est);
  // Where the layer memory cannot vouch: the followed layer's own peak within `agreement` [px]
  // of the steady length (a layer of the energy vector, tracking.layer_min_fraction of its
  // maximum, else the highest correlation peak) [px], or none.
  std::optional<double> followedLayerAtSteadyLength(const PairRegistration& r, double steady,
                                                    double agreement) const;
  // The shifts of the depth layers of pair 1-2 [px]: its translation energy peaks.
  std::vector<double> layerShifts(const PairRegistration& registration) const;
  std::vector<double> layerShifts(const std::vector<float>& translation_energy) const;
  // The length the motion so far predicts for pair 1-2 [px] (needs have01).
  double steadyLength(const Estimate& est) const { return motion01.shift() * est.frame_gap / gap01; }
  // Whether a pair whose followed layer is predicted to move by `followed` [px] can be
  // registered: even its slowest layer (of those pair 0-1 saw) must stay within
  // kMaxPairShiftFraction of N along both axes.
  bool shiftInReach(const cv::Point2d& followed) const;
  // The frame failed and the next one could not be registered against frame 1: the window
  // moves on to it, with the predicted step as its motion.
  void slideTo(WindowFrame&& frame, const PairMotion& predicted);
  // The rotation, zoom and translation that the motion so far predicts for a pair spanning
  // `intervals` frame intervals and `seconds` after frame 1, starting from `start` (pair 0-1
  // for pair 0-2); none without a motion or outside oefmt mode.
  std::optional<RegistrationPrior> predictedPair(int intervals, double seconds, const PairMotion* start) const;
  // A rotation measured otherwise (a gyro's) with its sigma in place of the prediction's.
  void takeTurn(RegistrationPrior& prior, double rotation, double sigma) const;
  // The prediction of a pair that no motion so far predicts (the first pair, or the first after a
  // restart): the vehicle held its heading and altitude. Its window is the turn the vehicle can
  // make and every zoom; where no peak of it registers the translation is tried with no turn and
  // no zoom, whose sigmas are how far they could be off and still leave a translation peak
  // standing out: about a pixel at the image's edge.
  RegistrationPrior stillPrior(double seconds) const {
    const int n = config.registration.size;
    RegistrationPrior still;
    still.rotation_window = std::min(maxRotation(seconds), CV_PI / 2.0);
    still.log_zoom_window = (n / 2 - 1) * registrar.logZoomPerBin();
    still.rotation_sigma = 2.0 / n;
    still.log_zoom_sigma = 2.0 / n;
    return still;
  }
  // The largest turn a pair spanning `seconds` can hold (the vehicle's yaw rate bound; none
  // outside the oefmt mode, or without an interval).
  double maxRotation(double seconds) const {
    if (config.mode != EstimatorMode::kOefmt || !(seconds > 0.0)) return CV_PI;
    return std::min(CV_PI, config.tracking.max_yaw_rate * seconds);
  }

  const EstimatorConfig& config;
  Registrar registrar;
  Registrar registrar02;  // pair 0-2, on its own thread: its own scratch, the shared tables
  std::future<PairRegistration> pending02;  // pair 0-2 started alongside pair 1-2
  std::optional<RegistrationPrior> prior02;  // its predicted rotation/zoom (read by the worker)
  std::optional<RegistrationPrior> prior12;  // pair 1-2's
  LocalOptimizer optimizer;
  PoseIntegrator integrator;
  MultiZoomTranslator multi_zoom;

  std::optional<WindowFrame> f0, f1;  // frames "0" and "1" of the window
  // Pair 0-1 (the previous step): integrated motion, energy vectors, raw zoom.
  bool have01 = false;
  PairMotion motion01;
  // The ground plane's tilt left in levelled views (the attitude source's error), from the
  // refined pairs' stretch (oefmt mode, while frames come levelled).
  PlaneTiltTracker plane_tilt;
  bool levelled = false;  // the newest frame came levelled
  std::vector<float> translation01;  // T01 (efmt: the fused multi-zoom profile)
  std::vector<float> zoom01;         // S01
  double raw_log_zoom01 = 0.0;
  double raw_log_zoom_sigma01 = 0.0;
  int gap01 = 1;

  int failed = 0;                       // consecutive frames that could not be registered
  std::optional<Pose4> anchor;          // the pose at frame 1 while later frames fail
  // The first of those frames, while it is the only one, and the step predicted for it (its pose
  // is the integrator's): the next frame is also tried against it (registerAfterFailedFrame).
  std::optional<WindowFrame> failed_frame;
  PairMotion failed_step;
  // The gyro's turn from frame 1 to the last frame pushed [rad] and its sigma (the frames between
  // failed): none where one of them came without a turn.
  std::optional<std::pair<double, double>> turn_since_f1 = std::make_pair(0.0, 0.0);
  std::optional<PairMotion> last_step;  // the last motion per frame interval
  // The followed layer's length per frame interval [px] when tracking was lost and the window
  // restarted, until the first pair after the restart is integrated (continueScale).
  std::optional<double> restart_length;
  // The last accepted motions per frame interval, newest last (kept through restarts: the
  // vehicle keeps moving while frames fail); the rotation/zoom prediction's source.
  std::deque<PairMotion> recent_steps;
  std::deque<PairMotion> recent_rates;  // of those, the steps whose rotation/zoom were measured
  detail::RateDeviations turn_deviations{kRateDeviationFrames, kRateDeviationSupport, kRateGateSpreads,
                                        kRateDeviationFloorBins * CV_PI / config.registration.size};
  detail::RateDeviations zoom_deviations{kRateDeviationFrames, kRateDeviationSupport, kRateGateSpreads,
                                        kRateDeviationFloorBins * registrar.logZoomPerBin()};
  int implausible_steps = 0;  // steps in a row replaced by the prediction (plausibleStep)
  // The followed layer's length against the layers in view over the last measured steps.
  LayerRatioMemory layer_ratios{kLayerRatioFrames, kLayerRatioSupport, kLayerRatioTolerance};
  int unconfirmed_steps = 0;  // steps in a row that did not enter recent_steps
  // The translations since the last start rest on a reading that a rival peak matched as well
  // (RegistrationPrior::translation_ambiguous), and how the prediction's peak fared against the
  // other readings since (RegistrationPrior::doubt_log_share).
  bool ambiguous_motion = false;
  double doubt_log_share = 0.0;
  bool started = false;
  double last_stamp = -std::numeric_limits<double>::infinity();

  // Runs pair 0-2. Last: destroyed (its task finished) before the frames and the registrar
  // that task reads.
  detail::WorkerThread worker02;
};

// While pair 0-2 runs on the worker it reads the newest frame, a local of Estimator::push: an
// exception that leaves push early must first wait for it.
class PendingPairGuard {
 public:
  explicit PendingPairGuard(std::future<PairRegistration>& pending)
      : pending_(pending), exceptions_(std::uncaught_exceptions()) {}
  ~PendingPairGuard() {
    if (std::uncaught_exceptions() > exceptions_ && pending_.valid()) {
      pending_.wait();
      pending_ = {};
    }
  }
  PendingPairGuard(const PendingPairGuard&) = delete;
  PendingPairGuard& operator=(const PendingPairGuard&) = delete;

 private:
  std::future<PairRegistration>& pending_;
  int exceptions_;
};

std::optional<RegistrationPrior> Estimator::State::predictedPair(int intervals, double seconds,
                                                                const PairMotion* start) const {
  if (config.mode != EstimatorMode::kOefmt || recent_steps.empty()) return std::nullopt;
  const int n = config.registration.size;
  // The turns and zooms come from the steps that measured them (a step on the predicted rotation
  // and zoom would only repeat the prediction), the translations from all the last steps.
  const std::deque<PairMotion>& rates = recent_rates.empty() ? recent_steps : recent_rates;
  // The median of the last steps' values: one wrong step does not move the prediction.
  const auto medianOfSteps = [](const std::deque<PairMotion>& steps, auto field) {
    std::vector<double> values;
    for (const PairMotion& m : steps) values.push_back(field(m));
    return medianOf(std::move(values));
  };
  const auto rate = [&](auto field) { return medianOfSteps(rates, field); };
  const auto median = [&](auto field) { return medianOfSteps(recent_steps, field); };
  RegistrationPrior prior;
  prior.rotation = rate([](const PairMotion& m) { return m.rotation; }) * intervals;
  prior.log_zoom = rate([](const PairMotion& m) { return m.log_zoom; }) * intervals;
  double rotation_sigma = rate([](const PairMotion& m) { return m.rotation_sigma; }) * intervals;
  double log_zoom_sigma = rate([](const PairMotion& m) { return m.log_zoom_sigma; }) * intervals;
  const double rotation12 = prior.rotation, log_zoom12 = prior.log_zoom;
  // The window's fixed part in rotation and ln zoom, and a third of it: a frame interval's
  // possible change of the rates.
  const double rotation_bins = kPriorWindowBins * CV_PI / n;
  const double log_zoom_bins = kPriorWindowBins * registrar.logZoomPerBin();
  // How far the last steps strayed from the median, plus a frame interval's change of the rates.
  double rotation_spread = 0.0, log_zoom_spread = 0.0;
  for (const PairMotion& m : rates) {
    rotation_spread = std::max(rotation_spread, std::fabs(m.rotation * intervals - rotation12));
    log_zoom_spread = std::max(log_zoom_spread, std::fabs(m.log_zoom * intervals - log_zoom12));
  }
  prior.rotation_spread = std::hypot(rotation_spread, rotation_bins / 3.0);
  prior.log_zoom_spread = std::hypot(log_zoom_spread, log_zoom_bins / 3.0);
  if (start != nullptr) {
    prior.rotation += start->rotation;
    prior.log_zoom += start->log_zoom;
    rotation_sigma = std::hypot(rotation_sigma, start->rotation_sigma);
    log_zoom_sigma = std::hypot(log_zoom_sigma, start->log_zoom_sigma);
  }
  prior.rotation_window = rotation_bins + 3.0 * rotation_sigma;
  prior.log_zoom_window = log_zoom_bins + 3.0 * log_zoom_sigma;
  // A registration on the prediction itself measured neither: the prediction's own sigma plus a
  // frame interval's change of the rates.
  prior.rotation_sigma = std::hypot(rotation_sigma, rotation_bins / 3.0);
  prior.log_zoom_sigma = std::hypot(log_zoom_sigma, log_zoom_bins / 3.0);
  if (last_step && seconds > 0.0) {
    // The translation per interval in the camera's axes: the median length of the last steps,
    // and the last direction turned on by the median turn between steps (steady in a
    // coordinated turn, turning steadily when the heading is held on a curve).
    const double length = median([](const PairMotion& m) { return m.shift(); });
    double direction = recent_steps.back().direction();
    double turn_spread = 0.0;
    if (recent_steps.size() >= 2) {
      std::vector<double> turns;
      for (std::size_t k = 1; k < recent_steps.size(); ++k) {
        turns.push_back(wrapToPi(recent_steps[k].direction() - recent_steps[k - 1].direction()));
      }
      const double turn = medianOf(turns);
      direction += turn;
      for (const double t : turns) turn_spread = std::max(turn_spread, std::fabs(t - turn));
    }
    const cv::Point2d per_interval = cv::Point2d(std::cos(direction), std::sin(direction)) * length;
    // How far the last steps strayed from it: along (their lengths) and across (their turns).
    double spread = 0.0;
    for (const PairMotion& m : recent_steps) spread = std::max(spread, std::fabs(m.shift() - length));
    spread = std::hypot(spread, turn_spread * length);
    prior.translation = per_interval * intervals;
    double uncertainty = spread * intervals;
    prior.translation_sigma = uncertainty;
    if (start != nullptr) {
      // d02 = s12 R(theta12) d01 + d12.
      prior.translation += rotateImageVector(start->translation, rotation12) * std::exp(log_zoom12);
      uncertainty += std::sqrt(std::max(cv::trace(start->translation_covariance), 0.0));
    }
    // The acceleration's reach in pixels is taken at the distance of the nearest content the
    // scene may hold: tracking.assumed_altitude, scaled as the vehicle climbs, or the altitude
    // where that is known and lower. Roofs and walls stand nearer than the ground the altitude
    // is measured to, and the window must also hold the prediction's own errors (a step of
    // another layer taken as the followed one's): at the true altitude of flights at 12-20 m it
    // was three to four times narrower, and periodic and walled flights drifted 1.2-2 % where
    // they drift 0.04-0.6 % without it (doc/results.md).
    const double relative_altitude = config.initial_altitude > 0.0
                                         ? integrator.altitude() / config.initial_altitude
                                         : integrator.altitude();
    double metres = config.tracking.assumed_altitude * relative_altitude;
    if (config.initial_altitude > 0.0) metres = std::min(metres, integrator.altitude());
    prior.translation_radius = config.effectiveFx() * config.tracking.max_acceleration * seconds * seconds /
                                   std::max(metres, 1e-6) +
                               3.0 * uncertainty + kTranslationWindowFloor;
  }
  return prior;
}

void Estimator::State::takeTurn(RegistrationPrior& prior, double rotation, double sigma) const {
  const double rotation_bins = kPriorWindowBins * CV_PI / config.registration.size;
  prior.rotation = rotation;
  prior.rotation_window = rotation_bins + 3.0 * sigma;
  prior.rotation_spread = std::hypot(sigma, rotation_bins / 3.0);
  prior.rotation_sigma = std::hypot(sigma, rotation_bins / 3.0);
}

bool Estimator::State::shiftInReach(const cv::Point2d& followed) const {
  // The slowest layer pair 0-1 saw (the farthest plane) moves the least.
  double fraction = 1.0;
  const double length01 = motion01.shift();
  if (have01 && length01 > 0.0) {
    for (const EnergyPeak& peak : energyPeaks(translation01, config.tracking.layer_min_fraction)) {
      fraction = std::min(fraction, peak.bin * registrar.shiftPerBin() / length01);
    }
  }
  const double limit = kMaxPairShiftFraction * config.registration.size;
  return std::fabs(followed.x * fraction) <= limit && std::fabs(followed.y * fraction) <= limit;
}

cv::Matx44d Estimator::State::heldGrowth() const {
  const double altitude = integrator.altitude();
  const double xy = kHeldPositionSigma * altitude, z = kHeldAltitudeSigma * altitude;
  return cv::Matx44d::diag(cv::Vec4d(xy * xy, xy * xy, z * z, kHeldYawSigma * kHeldYawSigma));
}

void Estimator::State::anchorFrame(WindowFrame&& frame, bool textured, Estimate& est) {
  plane_tilt.clear();  // its readings are in the axes of frames the new anchor has no turn to
  if (!started) {
    integrator.reset(frame.stamp);
    started = true;
    est.state = TrackingState::kStarted;
  } else {
    integrator.hold(frame.stamp, heldGrowth());
    est.state = TrackingState::kHeld;
  }
  if (textured) {
    f1 = std::move(frame);
  } else {
    est.degraded = true;
  }
}

void Estimator::State::registrationFailed(WindowFrame&& frame, bool textured, Estimate& est) {
  ++failed;
  est.degraded = true;
  failed_frame.reset();
  if (!anchor) anchor = integrator.pose();
  // The frame that restarts the window is predicted too: the vehicle kept moving while frames
  // failed, and a held pose would drop one step from the trajectory.
  if (config.tracking.predict_failed_frames && last_step && failed <= config.tracking.max_failed_frames + 1) {
    PairMotion predicted = detail::extrapolatedStep(*last_step, recent_rates);
    const double spread = config.tracking.prediction_sigma * predicted.shift();
    predicted.translation_covariance += cv::Matx22d::eye() * (spread * spread + 1.0);
    predicted.rotation_sigma = std::hypot(predicted.rotation_sigma, kPredictedRotationSigma);
    predicted.log_zoom_sigma = std::hypot(predicted.log_zoom_sigma, kPredictedLogZoomSigma);
    integrator.integrate(predicted, frame.stamp);
    est.state = TrackingState::kPredicted;
    // The next frame would be registered against frame 1 over one more interval: at low overlap
    // that pair is out of reach, and every later frame would fail too.
    if (failed <= config.tracking.max_failed_frames && textured && f1 &&
        !shiftInReach(last_step->translation * (static_cast<double>(frame.index - f1->index) + 1.0))) {
      slideTo(std::move(frame), predicted);
      return;
    }
    if (failed == 1 && failed <= config.tracking.max_failed_frames && textured) {
      failed_frame = std::move(frame);
      failed_step = predicted;
      return;
    }
  } else {
    integrator.hold(frame.stamp, heldGrowth());
    est.state = TrackingState::kHeld;
  }
  if (failed <= config.tracking.max_failed_frames) return;
  // Too long without a registration: restart from this frame, continuing from this pose.
  if (last_step && config.mode == EstimatorMode::kOefmt) restart_length = last_step->shift();
  startWindowOver();
  anchor.reset();
  last_step.reset();
  failed = 0;
  if (textured) {
    f1 = std::move(frame);
    est.state = TrackingState::kRestarted;
  } else {
    f1.reset();
  }
}

bool Estimator::State::registerAfterFailedFrame(const WindowFrame& frame, RegistrationMethod method,
                                                const std::optional<std::pair<double, double>>& turn,
                                                RegistrationSurfaces* surfaces, Estimate& est,
                                                double& rates_rotation12) {
  // This frame does not register against frame 1, two intervals back. One interval back, the
  // failed frame may: its view was not the trouble, only its pair with frame 1 (a layer or a
  // texture that filled that pair's view, a periodic texture's alias that won it). Its pose is
  // predicted, one interval from a measured one; chained from it, the track keeps that
  // prediction's error for good, which after more failed frames (a longer prediction, and a
  // motion model the measurements no longer confirm) would outweigh the frames it saves: then
  // the window restarts as before.
  if (config.mode != EstimatorMode::kOefmt || !failed_frame) return false;
  const double seconds = frame.stamp - failed_frame->stamp;
  std::optional<RegistrationPrior> prior = predictedPair(1, seconds, nullptr);
  const double rates_rotation = prior ? prior->rotation : 0.0;
  if (turn && prior) takeTurn(*prior, -turn->first, turn->second);  // the gyro's, over this interval
  RegistrationSurfaces retry_surfaces;
  PairRegistration retry = registrar.registerPair(failed_frame->spectra, frame.spectra, method,
                                                  surfaces ? &retry_surfaces : nullptr,
                                                  prior ? &*prior : nullptr, maxRotation(seconds));
  if (!retry.usable()) return false;
  if (pending02.valid()) pending02.wait();  // pair 0-2 of the old frame 0
  pending02 = {};
  slideTo(std::move(*failed_frame), failed_step);
  failed_frame.reset();
  est.frame_gap = static_cast<int>(frame.index - f1->index);
  prior12 = std::move(prior);
  rates_rotation12 = rates_rotation;
  est.prediction12 = prior12;
  est.registration12 = std::move(retry);
  if (surfaces) *surfaces = std::move(retry_surfaces);
  return true;
}

PairMotion Estimator::State::plausibleStep(const PairMotion& step, Estimate& est) {
  if (!prior12 || !(prior12->translation_radius > 0.0)) return step;
  const cv::Point2d off = step.translation - prior12->translation;
  if (cv::norm(off) <= prior12->translation_radius) {
    implausible_steps = 0;
    return step;
  }
  if (++implausible_steps > config.tracking.max_failed_frames) {
    // The measurements have disagreed with the model for longer than frames may fail: the
    // vehicle did change its motion. Believe them from here.
    implausible_steps = 0;
    forgetMotionModel();
    return step;
  }
  est.degraded = true;
  est.step_implausible = true;
  est.length_source = LengthSource::kImplausible;
  PairMotion predicted = step;
  predicted.translation = prior12->translation;
  const double spread = cv::norm(off);
  predicted.translation_covariance = step.translation_covariance + cv::Matx22d::eye() * (spread * spread);
  return predicted;
}

PairMotion Estimator::State::consistentRates(const PairMotion& step, double rates_rotation, bool gyro_turn,
                                             Estimate& est) {
  if (!prior12 || est.registration12.rotation_zoom_candidate == PairRegistration::kPredicted) return step;
  PairMotion out = step;
  // The turn is judged against the rates' extrapolation (`rates_rotation`). Where a gyro gave
  // the turn (then the prediction's rotation), a reading off the rates stands if the gyro is off
  // them too: the vehicle changed its rate. If the gyro kept to them, the extrapolation takes the
  // reading's place, as without a gyro: the gyro's bias stays out of it.
  const bool rate_changed =
      gyro_turn && turn_deviations.beyondGate(wrapToPi(prior12->rotation - rates_rotation));
  // A second turn in a row beyond the gate is a change of the rate only off a pair that
  // registered the followed layer itself. Where a layer or a pattern filling the view (tall brick
  // tops) leaves the pairs weak, their turns are read off it, in runs of either sign, and the
  // second of a run is no change of the rate.
  if (!rate_changed && turn_deviations.outlier(wrapToPi(step.rotation - rates_rotation),
                                               detail::lengthFromOwnPeak(est.length_source))) {
    est.turn_predicted = true;
    out.rotation = rates_rotation;
    out.rotation_sigma = std::hypot(turn_deviations.spread(), prior12->rotation_sigma);
  }
  if (zoom_deviations.outlier(step.log_zoom - prior12->log_zoom)) {
    est.zoom_predicted = true;
    out.log_zoom = prior12->log_zoom;
    out.log_zoom_sigma = std::hypot(zoom_deviations.spread(), prior12->log_zoom_sigma);
  } else if (est.registration12.zoom_refined && zoom_deviations.supported()) {
    // A refined zoom's sigma is calibrated (uncertainty.refined_log_zoom_scale), and the rates'
    // prediction is off by about the spread of the last readings' deviations from theirs (their
    // own errors included: the prediction is, if anything, better): the step takes the
    // inverse-variance mean of the two. A pair that pins its zoom closely keeps it; one over
    // several layers, whose sigma is tenths of a per cent, leans on the climb rate the last
    // steps agreed on, and the altitude does not take its error whole (doc/method.md).
    const double predicted = zoom_deviations.spread();
    const double measured = step.log_zoom_sigma;
    const double weight = predicted * predicted / (predicted * predicted + measured * measured);
    out.log_zoom = prior12->log_zoom + weight * (step.log_zoom - prior12->log_zoom);
    out.log_zoom_sigma = predicted * measured / std::hypot(predicted, measured);
  }
  if (est.turn_predicted || est.zoom_predicted) est.degraded = true;
  return out;
}

void Estimator::State::slideTo(WindowFrame&& frame, const PairMotion& predicted) {
  // Pair 0-1's energy vectors stay the scale reference (its speed is the one predicted).
  anchor.reset();
  motion01 = predicted;
  gap01 = 1;
  f0 = std::move(f1);
  f1 = std::move(frame);
}

bool Estimator::State::weighAmbiguity(Estimate& est) {
  const PairRegistration& r = est.registration12;
  if (!r.translation_unrivalled) {
    if (!(prior12 && prior12->translation_radius > 0.0)) {
      ambiguous_motion = r.uniqueness() < 1.0;
      doubt_log_share = 0.0;
    } else if (ambiguous_motion && prior12->translation_ambiguous && r.prediction_share > 0.0) {
      doubt_log_share += doubtLogShare(r.prediction_share);
    }
    return false;
  }
  ambiguous_motion = false;
  doubt_log_share = 0.0;
  if (!prior12 || !(cv::norm(r.translation - prior12->translation) > prior12->translation_radius)) return false;
  // The motion so far followed a periodic texture's alias: the window starts over from frame 1
  // with this pair, as after a restart (the poses before stay as integrated).
  if (pending02.valid()) pending02.wait();
  pending02 = {};
  startWindowOver();
  prior12.reset();
  est.alias_left = true;
  return true;
}

PairMotion Estimator::State::efmtStep(const WindowFrame& frame, Estimate& est,
                                      std::vector<float>& next_translation01) {
  PairMotion step = est.measured12;
  Clock::time_point t = Clock::now();
  MultiZoomTranslation mz = multi_zoom.analyse(f1->spectra, frame.spectra, est.registration12);
  est.registration_ms += msSince(t);
  if (!mz.valid) return step;
  const double shift_per_bin = registrar.shiftPerBin();
  // The unit length (first pair) is the dominant correlation peak's, as in oefmt's start-up;
  // later lengths follow it by PMT (or fall back to the fused profile's peak).
  double length = have01 ? refinedArgmax(mz.profile) * shift_per_bin : step.shift();
  double length_sigma = alongTrackSigma(step);
  if (have01) est.length_source = LengthSource::kEnergyPeak;
  if (have01 && !translation01.empty() &&
      motion01.shift() >= config.matching.min_peak_bins * shift_per_bin) {
    t = Clock::now();
    est.pmt12 = matchStretch(translation01, mz.profile,
                             detail::stretchOptions(config.matching, double(est.frame_gap) / gap01,
                                                    config.matching.stretch_key_12,
                                                    motion01.shift() / shift_per_bin));
    est.matching_ms = msSince(t);
    if (est.pmt12.valid) {
      est.length_source = LengthSource::kStretch;
      length = est.pmt12.value * motion01.shift();
      length_sigma = std::hypot(length * est.pmt12.sigma, est.pmt12.value * alongTrackSigma(motion01));
    }
  }
  step.translation = cv::Point2d(std::cos(mz.direction), std::sin(mz.direction)) * length;
  step.translation_covariance = alongAcrossCovariance(
      mz.direction, std::max(length_sigma, kMinShiftSigma),
      std::max(length * mz.direction_sigma * config.uncertainty.direction_scale, kMinShiftSigma));
  next_translation01 = std::move(mz.profile);
  return step;
}

PairMotion Estimator::State::oefmtStep(const WindowFrame& frame, Estimate& est, bool with02) {
  Clock::time_point t = Clock::now();
  if (with02) {
    est.registration02 = pending02.valid()
                             ? pending02.get()
                             : registrar02.registerPair(f0->spectra, frame.spectra,
                                                        RegistrationMethod::kEnergyVectors, nullptr,
                                                        prior02 ? &*prior02 : nullptr,
                                                        maxRotation(frame.stamp - f0->stamp));
    est.has_registration02 = true;
  }
  est.registration_ms += msSince(t);
  const PairRegistration& reg12 = est.registration12;
  const PairRegistration& reg02 = est.registration02;
  // Pair 0-2's translation spans twice the motion: at low overlap, or over a periodic texture
  // whose aliases stand as high, it fails where pair 1-2's registers. Its rotation/zoom peak reads
  // the magnitude spectra, which do not depend on the translation, and still closes the loop's
  // rotation. Nothing confirmed that peak, as a registered translation would have: it is taken
  // only within the gates of the rates' recent deviations, like pair 1-2's own turn and zoom
  // (consistentRates), and its rotation alone: such a pair's refined zoom erred over the corpus
  // several times as much as a registered pair's, its rotation about as little (doc/method.md).
  const bool rotation_only02 =
      with02 && !reg02.usable() && reg02.rotation_zoom_only && prior02 &&
      turn_deviations.withinGate(wrapToPi(reg02.rotation - prior02->rotation)) &&
      zoom_deviations.withinGate(std::log(reg02.zoom) - prior02->log_zoom);
  est.rotation_only02 = rotation_only02;
  const bool registered02 = with02 && reg02.usable();
  const bool usable02 = registered02 || rotation_only02;
  const double shift_per_bin = registrar.shiftPerBin();
  const double log_zoom_per_bin = registrar.logZoomPerBin();
  const int gap12 = est.frame_gap;
  const int gap02 = gap01 + gap12;
  detail::Reference ref;
  ref.translation = motion01.translation;
  ref.shift = motion01.shift();
  ref.shift_sigma = alongTrackSigma(motion01);
  ref.raw_log_zoom = raw_log_zoom01;
  ref.raw_log_zoom_sigma = raw_log_zoom_sigma01;
  ref.translation_energy = &translation01;

  // Pattern matching against pair 0-1's energy vectors: stretches ~ gap ratios, shifts ~ 0.
  const MatchingConfig& mc = config.matching;
  t = Clock::now();
  if (!translation01.empty() && ref.shift >= mc.min_peak_bins * shift_per_bin) {
    const double reference_bin = ref.shift / shift_per_bin;
    est.pmt12 = matchStretch(translation01, reg12.translation_energy,
                             detail::stretchOptions(mc, double(gap12) / gap01, mc.stretch_key_12,
                                                    reference_bin));
    if (registered02) {
      est.pmt02 = matchStretch(translation01, reg02.translation_energy,
                               detail::stretchOptions(mc, double(gap02) / gap01, mc.stretch_key_02,
                                                      reference_bin));
    }
  }
  if (!zoom01.empty()) {
    est.pms12 = matchShift(zoom01, reg12.zoom_energy, detail::shiftOptions(mc));
    if (registered02) est.pms02 = matchShift(zoom01, reg02.zoom_energy, detail::shiftOptions(mc));
    // A shift puts the pair's zoom at S01's plus the shift; outside the window the motion so
    // far predicts for the pair, it matched another feature of the vectors.
    const auto implausible = [&](const MatchResult& pms, const std::optional<RegistrationPrior>& prior) {
      const double log_zoom = raw_log_zoom01 - pms.value * log_zoom_per_bin;
      return prior && std::fabs(log_zoom - prior->log_zoom) > prior->log_zoom_window;
    };
    if (est.pms12.valid && implausible(est.pms12, prior12)) est.pms12.valid = false;
    if (est.pms02.valid && implausible(est.pms02, prior02)) est.pms02.valid = false;
  }
  est.matching_ms = msSince(t);

  PairMotion initial12;
  const PairObservations obs12 =
      detail::observe(reg12, est.measured12, est.pmt12, est.pms12, ref, config, shift_per_bin,
                      log_zoom_per_bin, double(gap12) / gap01, prior12 ? &*prior12 : nullptr, initial12,
                      /*skipped_frames=*/gap12 > 1);
  est.translation_use12 = obs12.translation_use;
  est.length_source = obs12.length_source;
  est.measured12 = initial12;
  // With a predicted translation the observations already follow the layer (observe()).
  const bool predicted_translation = prior12 && prior12->translation_radius > 0.0;
  const auto followLayer = [&](const PairMotion& candidate) {
    return predicted_translation ? candidate
                                 : detail::steadyLayerStep(candidate, reg12, translation01,
                                                           ref.shift * gap12 / gap01, config,
                                                           shift_per_bin, double(gap12) / gap01,
                                                           &est.length_source);
  };
  if (!usable02) return followLayer(initial12);  // no loop: the gated measurement

  // Pair 0-2's zoom is its registration's alone. Its zoom vector lies a whole pair's zoom (pair
  // 1-2's) away from pair 0-1's, a fraction of a bin that the matching locks toward the whole
  // bin: over weak texture nearly all of it (a climb then reads short), over the default texture
  // a seventh. Pair 1-2's lies only the change of the zoom rate away, about none in steady flight.
  // est.pms02 stays a diagnostic.
  PairMotion initial02;
  PairObservations obs02 = detail::observe(
      reg02, detail::calibrated(reg02, config.uncertainty), est.pmt02, MatchResult{}, ref, config,
      shift_per_bin, log_zoom_per_bin, double(gap02) / gap01, prior02 ? &*prior02 : nullptr, initial02);
  if (rotation_only02) {
    obs02.log_zoom.clear();
    obs02.translation_use = PairObservations::TranslationUse::kNone;
    obs02.shift.clear();
    obs02.translation_priors.clear();
  }
  est.translation_use02 = obs02.translation_use;
  t = Clock::now();
  est.loop = optimizer.solve(motion01, obs12, obs02, initial12, initial02);
  est.optimizer_ms = msSince(t);
  if (est.loop.status == OptimizerStatus::kConverged && !withinWindow(est.loop.pair12, prior12)) {
    // The loop bought its closure with a rotation or zoom the motion so far rules out (an outlier
    // elsewhere in the loop pulled a loosely measured value): the measurement stands.
    est.loop.status = OptimizerStatus::kFallback;
    est.loop.message = "rotation or zoom outside the predicted window";
  }
  if (rotation_only02) {
    // The loop closed the turn alone: pair 1-2 keeps its own zoom and length, as without a loop.
    // Otherwise the pair's other readings (its PMS zoom, the layers' lengths), which nothing
    // outside the pair weighs where pair 0-2 has no zoom or translation, would settle them.
    PairMotion step = initial12;
    if (est.loop.status == OptimizerStatus::kConverged) {
      step.rotation = est.loop.pair12.rotation;
      step.rotation_sigma = est.loop.pair12.rotation_sigma;
    }
    return followLayer(step);
  }
  if (est.loop.status != OptimizerStatus::kConverged) {
    est.degraded = true;
    return initial12;
  }
  if (ref.shift > 0.0) est.lambda_t02 = est.loop.pair02.shift() / ref.shift;
  if (std::fabs(est.loop.pair12.shift() - initial12.shift()) > config.tracking.layer_gate * initial12.shift()) {
    est.length_source = LengthSource::kLoop;
  }
  return followLayer(est.loop.pair12);
}

void Estimator::State::advance(WindowFrame&& frame, const PairMotion& step,
                               std::vector<float>&& next_translation01, Estimate& est) {
  const PairRegistration& measured = est.registration12;
  plane_tilt.turn(measured.rotation);
  if (levelled && measured.zoom_refined) plane_tilt.add(measured.stretch_a, measured.stretch_b, measured.translation);
  // Integrate, from the anchor if predictions were made while frames failed.
  if (anchor) integrator.restore(*anchor);
  // The pose takes the step with the spread of the lengths it could also have had (the PMT
  // stretch, the highest correlation peak) within the acceleration window: where they disagree
  // by more than a layer's noise the choice between them (a depth layer, a periodic texture's
  // alias) may be wrong, and the reported uncertainty says so. The next pair's reference keeps
  // the step's own covariance: the next steps are measured against the chosen length, right or
  // wrong, so the ambiguity belongs to the pose and not to the next ratio.
  if (have01 && motion01.shift() > 0.0) {
    std::vector<double> alternatives{cv::norm(est.registration12.translation)};
    if (est.pmt12.valid) alternatives.push_back(est.pmt12.value * motion01.shift());
    const double window = prior12 ? prior12->translation_radius : 0.0;
    est.length_spread = detail::lengthSpread(step.shift(), alternatives, config.tracking.layer_gate, window);
  }
  integrator.integrate(detail::withAlongTrackSpread(step, est.length_spread), frame.stamp);
  est.step = step;
  est.state = TrackingState::kTracking;
  if (have01 && motion01.shift() > 0.0) est.lambda_t12 = step.shift() / motion01.shift();

  // Slide the window: the integrated 1-2 becomes the next 0-1.
  last_step = detail::perInterval(step, est.frame_gap);
  // A prediction standing in for a step (or for its direction) says nothing new. When the
  // measurements keep disagreeing with the prediction for longer than frames may fail, the motion
  // changed: the model starts over from the measurements.
  if (!est.step_implausible && est.translation_use12 != PairObservations::TranslationUse::kNone) {
    recent_steps.push_back(*last_step);
    if (recent_steps.size() > kPredictionSteps) recent_steps.pop_front();
    if (config.mode == EstimatorMode::kOefmt) layer_ratios.remember(step.shift(), layerShifts(est.registration12));
    if (est.registration12.rotation_zoom_candidate != PairRegistration::kPredicted) {
      recent_rates.push_back(*last_step);
      if (recent_rates.size() > kPredictionSteps) recent_rates.pop_front();
    }
    unconfirmed_steps = 0;
  } else if (++unconfirmed_steps > config.tracking.max_failed_frames) {
    forgetMotionModel();
    unconfirmed_steps = 0;
  }
  motion01 = step;
  translation01 = std::move(next_translation01);
  zoom01 = est.registration12.zoom_energy;
  raw_log_zoom01 = est.measured12.log_zoom;
  raw_log_zoom_sigma01 = est.measured12.log_zoom_sigma;
  gap01 = est.frame_gap;
  have01 = true;
  failed = 0;
  anchor.reset();
  failed_frame.reset();
  f0 = std::move(f1);
  f1 = std::move(frame);
}

std::vector<double> Estimator::State::layerShifts(const PairRegistration& registration) const {
  return layerShifts(registration.translation_energy);
}

std::vector<double> Estimator::State::layerShifts(const std::vector<float>& translation_energy) const {
  std::vector<double> shifts;
  const double shift_per_bin = registrar.shiftPerBin();
  for (const EnergyPeak& peak : energyPeaks(translation_energy, config.tracking.layer_min_fraction)) {
    shifts.push_back(peak.bin * shift_per_bin);
  }
  return shifts;
}

PairMotion Estimator::State::vouchedStep(const PairMotion& step, Estimate& est) const {
  const double length = step.shift();
  if (!have01 || !(length > 0.0)) return step;
  const double steady = steadyLength(est);
  const std::optional<double> vouched = layer_ratios.vouchedLength(layerShifts(est.registration12), steady);
  if (!vouched || !detail::vouchedLengthWins(length, est.length_source, *vouched, steady, config.tracking.layer_gate,
                                             kLayerRatioTolerance)) {
    return step;
  }
  est.vouched_length = *vouched;
  est.length_source = LengthSource::kVouched;
  return atVouchedLength(step, *vouched);
}

void Estimator::State::continueScale(const PairMotion& step, const Estimate& est) {
  // A restart follows its first pair's highest peak, and a pair has no scale of its own: where
  // that peak is another depth layer than the one followed before (the ground instead of the
  // roofs), every later step kept the two layers' depth ratio as a wrong scale. The vehicle kept
  // its speed over the few frames that failed (their poses were predicted so): the new layer is
  // taken at the depth that gives the pair the length per interval the followed layer had, where
  // the two lengths differ by no more than two depth layers' shifts can (kMaxDepthLayerRatio;
  // further apart, the peak is an alias or the speed did change).
  const std::optional<double> before = restart_length;
  restart_length.reset();
  const double length = step.shift();
  if (!before || !(*before > 0.0) || !(length > 0.0) || have01) return;
  const double depth_ratio = *before * est.frame_gap / length;
  if (depth_ratio > kMaxDepthLayerRatio || depth_ratio < 1.0 / kMaxDepthLayerRatio) return;
  integrator.moveReferencePlane(depth_ratio);
}

std::optional<PairMotion> Estimator::State::corroboratedStep(Estimate& est) const {
  // Where one depth layer fills most of the view, its texture (oriented, periodic) can leave the
  // translation peak too flat to trust on its own, while the layers in its energy vector still
  // stand at the depth ratios they held. A length they vouch for that the motion so far also
  // predicts (within twice the ratios' own tolerance) is two independent readings agreeing: the
  // pair is tracked on it instead of being lost. A noise peak would need to fall, with its
  // direction, in the acceleration window and at a held ratio of the predicted length (or, before
  // the ratios hold, within 2 % of the predicted length itself).
  const PairRegistration& r = est.registration12;
  if (!have01 || !prior12 || !(prior12->translation_radius > 0.0) ||
      r.status != RegistrationStatus::kLowConfidence || !(r.peak_confidence > 0.0) ||
      r.rotation_zoom_implausible || !(r.shift > 0.0)) {
    return std::nullopt;
  }
  const double steady = steadyLength(est);
  const double agreement = 2.0 * kLayerRatioTolerance * steady;
  double vouched_length = 0.0;
  const std::optional<LayerRatioMemory::Vouched> held = layer_ratios.vouch(layerShifts(r), steady);
  if (held && std::fabs(held->length - steady) <= agreement) {
    vouched_length = held->length;
  } else if (const std::optional<double> own = followedLayerAtSteadyLength(r, steady, agreement)) {
    vouched_length = *own;
  }
  if (!(vouched_length > 0.0)) return std::nullopt;
  const PairMotion measured = detail::calibrated(r, config.uncertainty);
  const PairMotion step = atVouchedLength(measured, vouched_length);
  if (!(cv::norm(step.translation - prior12->translation) <= prior12->translation_radius)) return std::nullopt;
  est.measured12 = measured;
  est.vouched_length = vouched_length;
  est.length_source = LengthSource::kVouched;
  return step;
}

std::optional<PairMotion> Estimator::State::corroboratedAlongPrediction(const WindowFrame& frame, Estimate& est) {
  // corroboratedStep reads the layers along the chosen peak's direction. Over a periodic texture
  // that peak may be an alias in another direction altogether (near zero shift, where every
  // direction's row passes), with no confidence: the layers are then looked for along the
  // predicted direction, and the same two readings must agree (a length the held depth ratios
  // vouch for, within twice their tolerance of the predicted one). The step takes the predicted
  // direction, with the prediction's own spread across it.
  const PairRegistration& r = est.registration12;
  if (!have01 || !prior12 || !(prior12->translation_radius > 0.0) ||
      r.status != RegistrationStatus::kLowConfidence || r.rotation_zoom_implausible) {
    return std::nullopt;
  }
  const double predicted = cv::norm(prior12->translation);
  if (!(predicted > 0.0)) return std::nullopt;
  const double steady = steadyLength(est);
  const double agreement = 2.0 * kLayerRatioTolerance * steady;
  const double direction = std::atan2(prior12->translation.y, prior12->translation.x);
  // Empty unless the registrar's last surface is this pair's (a retry after a failed frame
  // registers another pair).
  std::vector<float> energy = registrar.translationEnergyAlong(f1->spectra, frame.spectra, direction, predicted);
  const std::optional<LayerRatioMemory::Vouched> held = layer_ratios.vouch(layerShifts(energy), steady);
  if (!held || !(std::fabs(held->length - steady) <= agreement)) return std::nullopt;
  PairMotion step = detail::calibrated(r, config.uncertainty);
  step.translation = prior12->translation * (held->length / predicted);
  step.translation_covariance =
      alongAcrossCovariance(direction, std::max(kLayerRatioTolerance * held->length, detail::kMinShiftSigma),
                            std::max(prior12->translation_sigma, detail::kMinShiftSigma));
  est.measured12 = step;
  est.vouched_length = held->length;
  est.length_source = LengthSource::kVouched;
  // The layers remembered with this step, and the next pair's pattern matching, read these.
  est.registration12.translation_energy = std::move(energy);
  return step;
}

std::optional<double> Estimator::State::followedLayerAtSteadyLength(const PairRegistration& r, double steady,
                                                                    double agreement) const {
  // The memory vouches for nothing while the layers in view are new to it (it needs most of a
  // window of steps) and for a wrong length while they are settling. Then the followed layer's own
  // peak at the predicted length stands for it: in the energy vector, or as the pair's highest
  // correlation peak. It must sit as close to the prediction as a held ratio must.
  const double shift_per_bin = registrar.shiftPerBin();
  if (shift_per_bin > 0.0) {
    if (const std::optional<double> bin = peakNear(r.translation_energy, steady / shift_per_bin,
                                                   agreement / shift_per_bin,
                                                   config.tracking.layer_min_fraction)) {
      return *bin * shift_per_bin;
    }
  }
  if (std::fabs(r.shift - steady) <= agreement) return r.shift;
  return std::nullopt;
}

Estimator::Estimator(const EstimatorConfig& config) : config_(config) {
  config_.validate();
  state_ = std::make_unique<State>(config_, std::make_shared<const SpectralContext>(config_.modeRegistration()));
}

Estimator::Estimator(const EstimatorConfig& config, std::shared_ptr<const SpectralContext> context)
    : config_(config) {
  config_.validate();
  if (!context || context->config() != config_.modeRegistration()) {
    throw InputError("Estimator: the spectral context was made for other registration parameters");
  }
  state_ = std::make_unique<State>(config_, std::move(context));
}

std::shared_ptr<const SpectralContext> Estimator::spectralContext() const {
  return state_->registrar.sharedContext();
}

Estimator::~Estimator() = default;

void Estimator::reset() {
  state_->clear();
  frame_count_ = 0;
  turn_.reset();
  levelled_ = false;
}

void Estimator::setTurn(double turn, double sigma) {
  if (std::isfinite(turn) && std::isfinite(sigma) && sigma >= 0.0) turn_ = std::make_pair(turn, sigma);
}

const Pose4& Estimator::pose() const { return state_->integrator.pose(); }

double Estimator::altitude() const { return state_->integrator.altitude(); }

void Estimator::observeAltitude(double altitude, double sigma, double drift_variance) {
  State& s = *state_;
  const double before = s.integrator.pose().z;
  if (drift_variance > 0.0 && std::isfinite(drift_variance)) {
    Pose4 widened = s.integrator.pose();
    widened.covariance(2, 2) += drift_variance;
    s.integrator.restore(widened);
  }
  s.integrator.correctAltitude(altitude, sigma * sigma);
  // Predictions made while frames failed are undone from the anchor: it moves alike.
  if (s.anchor) s.anchor->z += s.integrator.pose().z - before;
}
void Estimator::rescale(double factor) {
  if (!std::isfinite(factor) || !(factor > 0.0)) return;
  State& s = *state_;
  s.integrator.rescale(factor);
  if (s.anchor) *s.anchor = rescaled(*s.anchor, factor);
}

double Estimator::shiftPerBin() const { return state_->registrar.shiftPerBin(); }
double Estimator::logZoomPerBin() const { return state_->registrar.logZoomPerBin(); }

std::optional<double> Estimator::centreDepthRatio(cv::Point2d beam) const {
  const State& s = *state_;
  if (!s.have01 || !s.f0 || !s.f1) return std::nullopt;
  return oefmt::centreDepthRatio(s.f0->spectra.grey, s.f1->spectra.grey, s.motion01, beam);
}

bool Estimator::acceptsStamp(double stamp) const {
  return std::isfinite(stamp) && stamp >= state_->last_stamp;
}

std::optional<Estimate> Estimator::push(const cv::Mat& image, double stamp, ChannelOrder order) {
  if (!acceptsStamp(stamp)) return std::nullopt;
  const Clock::time_point start = Clock::now();
  FrameSpectra spectra = state_->registrar.analyse(image, order);
  return process(std::move(spectra), stamp, msSince(start));
}

std::optional<Estimate> Estimator::push(const PreparedImage& image, double stamp) {
  if (!acceptsStamp(stamp)) return std::nullopt;
  const Clock::time_point start = Clock::now();
  FrameSpectra spectra = state_->registrar.analyse(image);
  return process(std::move(spectra), stamp, msSince(start));
}

std::optional<Estimate> Estimator::push(FrameSpectra spectra, double stamp) {
  const int n = config_.registration.size;
  if (spectra.empty() || spectra.grey.rows != n || spectra.grey.cols != n ||
      spectra.spectrum.rows != n || spectra.log_polar_spectrum.rows != n) {
    throw InputError("Estimator: the frame's spectra are empty or not of size " + std::to_string(n));
  }
  if (!acceptsStamp(stamp)) return std::nullopt;
  return process(std::move(spectra), stamp, 0.0);
}

std::optional<Estimate> Estimator::process(FrameSpectra spectra, double stamp, double prepare_ms) {
  const Clock::time_point start = Clock::now();
  State& s = *state_;
  Estimate est;
  est.frame_index = frame_count_++;
  est.stamp = stamp;
  est.mode = config_.mode;
  est.registration_ms = prepare_ms;
  s.last_stamp = stamp;
  const bool textured = std::isfinite(spectra.texture) &&
                        spectra.texture >= config_.registration.min_texture;
  WindowFrame frame{std::move(spectra), est.frame_index, stamp};
  const std::optional<std::pair<double, double>> turn = std::exchange(turn_, std::nullopt);  // this frame's only
  const bool levelled = std::exchange(levelled_, false);

  if (!s.f1) {
    s.anchorFrame(std::move(frame), textured, est);
  } else {
    est.frame_gap = static_cast<int>(frame.index - s.f1->index);
    const RegistrationMethod method = config_.mode == EstimatorMode::kFmt
                                          ? RegistrationMethod::kClassic
                                          : RegistrationMethod::kEnergyVectors;
    const Clock::time_point t = Clock::now();
    const double seconds12 = frame.stamp - s.f1->stamp;
    bool with02 = config_.mode == EstimatorMode::kOefmt && s.f0 && s.have01 &&
                        s.shiftInReach(s.motion01.translation * (double(s.gap01 + est.frame_gap) / s.gap01));
    s.prior02 = with02 ? s.predictedPair(est.frame_gap, seconds12, &s.motion01) : std::nullopt;
    // Where pair 0-2's translation fails, its rotation may still close the loop (oefmtStep).
    if (s.prior02) s.prior02->rotation_zoom_alone = true;
    // Levelled frames: the zooms are corrected for the tilt the attitude source left (zero until
    // the readings tell it). A frame levelled or not unlike the one before starts the readings
    // over: they describe another view.
    if (levelled != s.levelled) s.plane_tilt.clear();
    s.levelled = levelled;
    const std::optional<cv::Point2d> plane_tilt =
        levelled && config_.mode == EstimatorMode::kOefmt ? std::optional<cv::Point2d>(s.plane_tilt.tilt())
                                                          : std::nullopt;
    s.registrar.setPlaneTilt(plane_tilt);
    s.registrar02.setPlaneTilt(plane_tilt);
    if (plane_tilt) est.plane_tilt = *plane_tilt * config_.effectiveFx();
    // A gyro's turn stands for the predicted rotation (the image turns against the camera). Its
    // turn spans the last interval; after failed frames, pair 1-2 spans theirs too. A gyro's error
    // is mostly its bias: the intervals' sigmas add.
    const std::optional<std::pair<double, double>> turn12 =
        turn && s.turn_since_f1 ? std::make_optional(std::make_pair(s.turn_since_f1->first + turn->first,
                                                                    s.turn_since_f1->second + turn->second))
                                : std::nullopt;
    if (turn12 && s.prior02) {
      s.takeTurn(*s.prior02, s.motion01.rotation - turn12->first,
                 std::hypot(turn12->second, s.motion01.rotation_sigma));
    }
    if (with02 && config_.parallel_registrations) {
      // Pair 0-2 on a second thread while this one registers 1-2 (both read the frames'
      // cached spectra; each Registrar has its own scratch). Collected in oefmtStep; discarded
      // if pair 1-2 fails.
      const FrameSpectra& older = s.f0->spectra;
      const FrameSpectra& newer = frame.spectra;
      const double max_rotation02 = s.maxRotation(frame.stamp - s.f0->stamp);
      s.pending02 = s.worker02.submit([&s, &older, &newer, max_rotation02] {
        return s.registrar02.registerPair(older, newer, RegistrationMethod::kEnergyVectors, nullptr,
                                          s.prior02 ? &*s.prior02 : nullptr, max_rotation02);
      });
    }
    const PendingPairGuard pending_guard(s.pending02);
    RegistrationSurfaces* surfaces = nullptr;
    if (keep_surfaces_) surfaces = &est.surfaces12.emplace();
    s.prior12 = s.predictedPair(est.frame_gap, seconds12, nullptr);
    if (s.prior12) {
      // A pair 1-2 whose translation fails may still be carried by its layers (corroboratedStep):
      // with the rotation and zoom refined from the predicted translation, not the surface peak's.
      s.prior12->rotation_zoom_alone = true;
      s.prior12->translation_ambiguous = s.ambiguous_motion;
      s.prior12->doubt_log_share = s.doubt_log_share;
    }
    double rates_rotation12 = s.prior12 ? s.prior12->rotation : 0.0;
    if (turn12 && s.prior12) s.takeTurn(*s.prior12, -turn12->first, turn12->second);
    bool gyro_turn12 = turn12.has_value();
    est.prediction12 = s.prior12;
    est.registration12 = s.registrar.registerPair(s.f1->spectra, frame.spectra, method, surfaces,
                                                  s.prior12 ? &*s.prior12 : nullptr,
                                                  s.maxRotation(seconds12));
    // A pair that found no rotation of its own takes the predicted one. The window is centred on
    // the median of the last turns, robust to one wrong turn, but a turn that grows or shrinks
    // steadily (a figure-8 flown with the heading on the track) has moved on by one and a half
    // steps' change since that median: the turn continued at its steady change is the better
    // guess. A gyro's turn, where one was given, stands.
    if (!gyro_turn12 && s.prior12 && est.registration12.rotation_zoom_candidate == PairRegistration::kPredicted) {
      if (const std::optional<double> turn = detail::steadilyChangingTurn(s.recent_rates)) {
        est.registration12.rotation = wrapToPi(*turn * est.frame_gap);
      }
    }
    if (!est.registration12.usable() && !s.prior12 && config_.mode == EstimatorMode::kOefmt) {
      // Nothing predicted this pair and the rotation/zoom surface's highest peaks did not
      // register (at low overlap the shared part of two frames is small, and a wrong peak can be
      // the highest): the vehicle may simply have held its heading and altitude.
      const RegistrationPrior still = s.stillPrior(seconds12);
      RegistrationSurfaces still_surfaces;
      PairRegistration retry = s.registrar.registerPair(s.f1->spectra, frame.spectra, method,
                                                        surfaces ? &still_surfaces : nullptr, &still,
                                                        s.maxRotation(seconds12));
      if (retry.peak_confidence > est.registration12.peak_confidence) {
        est.registration12 = std::move(retry);
        if (surfaces) *surfaces = std::move(still_surfaces);
      }
    }
    if (!est.registration12.usable() &&
        s.registerAfterFailedFrame(frame, method, turn, surfaces, est, rates_rotation12)) {
      with02 = false;
      gyro_turn12 = turn.has_value();
    }
    est.registration_ms += msSince(t);
    if (!est.registration12.usable()) {
      // Pair 0-2 and the loop are left out, also for a pair its layers carry: they would be weighed
      // against a weak pair. (The worker reads `frame`, which moves on below.)
      if (s.pending02.valid()) s.pending02.wait();
      s.pending02 = {};
      std::optional<PairMotion> corroborated =
          config_.mode == EstimatorMode::kOefmt ? s.corroboratedStep(est) : std::nullopt;
      if (!corroborated && config_.mode == EstimatorMode::kOefmt) corroborated = s.corroboratedAlongPrediction(frame, est);
      if (corroborated) {
        est.degraded = true;
        s.advance(std::move(frame), *corroborated, std::vector<float>(est.registration12.translation_energy), est);
      } else {
        s.registrationFailed(std::move(frame), textured, est);
      }
    } else {
      if (s.weighAmbiguity(est)) with02 = false;
      est.measured12 = detail::calibrated(est.registration12, config_.uncertainty);
      std::vector<float> next_translation01 = est.registration12.translation_energy;
      PairMotion step = est.measured12;
      est.length_source = LengthSource::kPeak;
      if (config_.mode == EstimatorMode::kEfmt) {
        step = s.efmtStep(frame, est, next_translation01);
      } else if (config_.mode == EstimatorMode::kOefmt && s.f0 && s.have01) {
        step = s.oefmtStep(frame, est, with02);
      }
      if (config_.mode == EstimatorMode::kOefmt) {
        step = s.consistentRates(s.plausibleStep(s.vouchedStep(step, est), est), rates_rotation12,
                                gyro_turn12, est);
        s.continueScale(step, est);
      }
      s.advance(std::move(frame), step, std::move(next_translation01), est);
    }
    s.turn_since_f1 = turn12;  // unless this frame became frame 1 (below), the next pair spans it
  }
  if (!s.f1 || s.f1->index == est.frame_index) s.turn_since_f1 = std::make_pair(0.0, 0.0);
  // A kept frame is only ever the older one of a pair from now on: its correlations as the
  // newer one (computed ahead, FrameSpectra::correlated) are of no more use.
  if (s.f1) s.f1->spectra.correlated.clear();
  est.pose = s.integrator.pose();
  if (est.state != TrackingState::kStarted) est.step_covariance = s.integrator.lastStepCovariance();
  est.total_ms = prepare_ms + msSince(start);
  est.estimator_ms = std::max(0.0, est.total_ms - est.registration_ms);
  return std::optional<Estimate>(std::move(est));
}

}  // namespace oefmt
