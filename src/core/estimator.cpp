// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/estimator.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

#include "oefmt/error.h"
#include "oefmt/multi_zoom.h"

namespace oefmt {
namespace {

using Clock = std::chrono::steady_clock;

double msSince(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// Smallest sigmas handed on, so that no weight becomes infinite.
constexpr double kMinRotationSigma = 1e-5;  // [rad]
constexpr double kMinLogZoomSigma = 1e-5;
constexpr double kMinShiftSigma = 0.01;     // [px]
// Growth of a held pose per frame, relative to the altitude (x, y, z) and in rad (yaw): large on
// purpose, the camera may have moved anywhere.
constexpr double kHeldPositionSigma = 0.1;
constexpr double kHeldAltitudeSigma = 0.05;
constexpr double kHeldYawSigma = 0.1;
// Extra sigmas of a predicted step's rotation [rad] and log-zoom.
constexpr double kPredictedRotationSigma = 0.05;
constexpr double kPredictedLogZoomSigma = 0.05;

struct WindowFrame {
  FrameSpectra spectra;
  std::size_t index = 0;
  double stamp = 0.0;
};

double finiteOr(double v, double fallback) { return std::isfinite(v) ? v : fallback; }

// A registration as a PairMotion with its peak widths turned into error sigmas.
PairMotion calibrated(const PairRegistration& r, const UncertaintyConfig& u) {
  PairMotion m;
  m.rotation = wrapToPi(finiteOr(r.rotation, 0.0));
  m.log_zoom = r.zoom > 0.0 && std::isfinite(r.zoom) ? std::log(r.zoom) : 0.0;
  m.translation = {finiteOr(r.translation.x, 0.0), finiteOr(r.translation.y, 0.0)};
  m.rotation_sigma = std::max(finiteOr(r.rotation_sigma, CV_PI) * u.rotation_scale, kMinRotationSigma);
  m.log_zoom_sigma = std::max(finiteOr(r.log_zoom_sigma, 1.0) * u.log_zoom_scale, kMinLogZoomSigma);
  const double shift = m.shift();
  const double along = std::max(finiteOr(r.shift_sigma, 1e3) * u.shift_scale, kMinShiftSigma);
  const double across = shift >= 1.0
                            ? std::max(shift * finiteOr(r.direction_sigma, CV_PI) * u.direction_scale,
                                       kMinShiftSigma)
                            : along;
  m.translation_covariance = alongAcrossCovariance(m.direction(), along, across);
  return m;
}

// 1-sigma of |d| (along d).
double alongTrackSigma(const PairMotion& m) {
  const cv::Matx22d& c = m.translation_covariance;
  const double length = m.shift();
  if (!(length > 1e-9)) return std::sqrt(std::max(0.5 * (c(0, 0) + c(1, 1)), 0.0));
  const double ux = m.translation.x / length, uy = m.translation.y / length;
  return std::sqrt(std::max(ux * ux * c(0, 0) + 2.0 * ux * uy * c(0, 1) + uy * uy * c(1, 1), 0.0));
}

// The motion of one frame interval from a motion spanning `gap` intervals.
PairMotion perInterval(const PairMotion& m, int gap) {
  if (gap <= 1) return m;
  PairMotion out = m;
  out.rotation /= gap;
  out.log_zoom /= gap;
  out.translation = m.translation * (1.0 / gap);
  out.translation_covariance = m.translation_covariance * (1.0 / (gap * gap));
  return out;
}

StretchMatchOptions stretchOptions(const MatchingConfig& m, double init, double key,
                                   double reference_bin) {
  StretchMatchOptions o;
  o.skip_bins = reference_bin > 4.0 * m.skip_bins ? m.skip_bins : 0;
  o.steps = m.stretch_steps;
  o.key = key;
  o.init = init;
  o.init_window = m.stretch_init_window;
  o.max_normalised_error = m.max_normalised_error;
  o.smoothing_sigma = m.smoothing_sigma;
  o.sigma_floor = m.stretch_sigma_floor;
  return o;
}

ShiftMatchOptions shiftOptions(const MatchingConfig& m) {
  ShiftMatchOptions o;
  o.max_shift = m.shift_range;
  o.step = m.shift_step;
  o.max_normalised_error = m.max_normalised_error;
  o.smoothing_sigma = m.smoothing_sigma;
  o.sigma_floor = m.shift_sigma_floor;
  return o;
}

}  // namespace

const char* toString(TrackingState state) {
  switch (state) {
    case TrackingState::kStarted: return "started";
    case TrackingState::kTracking: return "tracking";
    case TrackingState::kPredicted: return "predicted";
    case TrackingState::kHeld: return "held";
    case TrackingState::kRestarted: return "restarted";
  }
  return "unknown";
}

// Everything that changes from frame to frame, plus the per-size machinery.
struct Estimator::State {
  explicit State(const EstimatorConfig& c)
      : registrar(c.registration),
        optimizer(c.optimizer),
        integrator(c.initialAltitude(), c.effectiveFx()),
        multi_zoom(registrar.sharedContext(), c.efmt) {}

  void clear() {
    f0.reset();
    f1.reset();
    forgetPair01();
    failed = 0;
    anchor.reset();
    last_step.reset();
    started = false;
    last_stamp = -std::numeric_limits<double>::infinity();
  }
  void forgetPair01() {
    have01 = false;
    translation01.clear();
    zoom01.clear();
  }

  Registrar registrar;
  LocalOptimizer optimizer;
  PoseIntegrator integrator;
  MultiZoomTranslator multi_zoom;

  std::optional<WindowFrame> f0, f1;  // frames "0" and "1" of the window
  // Pair 0-1 (the previous step): integrated motion, energy vectors, raw zoom.
  bool have01 = false;
  PairMotion motion01;
  std::vector<float> translation01;  // T01 (efmt: the fused multi-zoom profile)
  std::vector<float> zoom01;         // S01
  double raw_log_zoom01 = 0.0;
  double raw_log_zoom_sigma01 = 0.0;
  int gap01 = 1;

  int failed = 0;                      // consecutive frames that could not be registered
  std::optional<Pose4> anchor;         // the pose at frame 1 while later frames fail
  std::optional<PairMotion> last_step; // the last motion per frame interval
  bool started = false;
  double last_stamp = -std::numeric_limits<double>::infinity();
};

Estimator::Estimator(const EstimatorConfig& config) : config_(config) {
  config_.validate();
  state_ = std::make_unique<State>(config_);
}

Estimator::~Estimator() = default;

void Estimator::reset() {
  state_->clear();
  frame_count_ = 0;
}

const Pose4& Estimator::pose() const { return state_->integrator.pose(); }
double Estimator::shiftPerBin() const { return state_->registrar.shiftPerBin(); }
double Estimator::logZoomPerBin() const { return state_->registrar.logZoomPerBin(); }

std::optional<Estimate> Estimator::push(const cv::Mat& image, double stamp, ChannelOrder order) {
  if (!std::isfinite(stamp) || stamp < state_->last_stamp) return std::nullopt;
  const Clock::time_point start = Clock::now();
  FrameSpectra spectra = state_->registrar.analyse(image, order);
  return process(std::move(spectra), stamp, msSince(start));
}

std::optional<Estimate> Estimator::push(const PreparedImage& image, double stamp) {
  if (!std::isfinite(stamp) || stamp < state_->last_stamp) return std::nullopt;
  const Clock::time_point start = Clock::now();
  FrameSpectra spectra = state_->registrar.analyse(image);
  return process(std::move(spectra), stamp, msSince(start));
}

namespace {

// What the oefmt step needs to know about pair 0-1 when it builds a pair's observations.
struct Reference {
  cv::Point2d translation;   // d01 [px of frame 1]
  double shift = 0.0;        // |d01| [px of frame 1]
  double shift_sigma = 0.0;  // its 1-sigma
  double raw_log_zoom = 0.0; // ln s of the registration that made S01
  double raw_log_zoom_sigma = 0.0;
};

// The observations of one pair (1-2 or 0-2) for the optimizer, and its starting value. The
// correlation peak's length is checked against the PMT prediction: a length off by more than
// layer_gate belongs to another depth layer (or an alias), so only the peak's direction is kept,
// and the translation energy peak nearest to the prediction (the followed layer) gives the length.
PairObservations observe(const PairRegistration& registration, const PairMotion& measured,
                         const MatchResult& pmt, const MatchResult& pms, const Reference& ref,
                         const EstimatorConfig& config, double shift_per_bin,
                         double log_zoom_per_bin, double intervals, PairMotion& initial) {
  PairObservations obs = PairObservations::fromMotion(measured);
  initial = measured;
  if (config.tracking.motion_prior_sigma > 0.0) {
    // Pair 0-1's motion continued over this pair's frame intervals.
    const cv::Point2d predicted = ref.translation * intervals;
    const double sigma = config.tracking.motion_prior_sigma * cv::norm(predicted) + 1.0;
    obs.translation_priors.push_back({predicted, cv::Matx22d::eye() * (sigma * sigma)});
  }
  if (pms.valid) {
    obs.log_zoom.push_back({ref.raw_log_zoom - pms.value * log_zoom_per_bin,
                            std::hypot(pms.sigma * log_zoom_per_bin, ref.raw_log_zoom_sigma)});
  }
  if (!pmt.valid) return obs;
  const double predicted = pmt.value * ref.shift;
  const double predicted_sigma = std::hypot(predicted * pmt.sigma, pmt.value * ref.shift_sigma);
  obs.shift.push_back({predicted, predicted_sigma});
  const double measured_shift = measured.shift();
  if (std::fabs(measured_shift - predicted) <= config.tracking.layer_gate * predicted) return obs;

  obs.translation_use = PairObservations::TranslationUse::kDirection;
  double length = predicted;
  double length_sigma = predicted_sigma;
  const std::optional<double> bin =
      peakNear(registration.translation_energy, predicted / shift_per_bin,
               config.tracking.layer_search * predicted / shift_per_bin,
               config.tracking.layer_min_fraction);
  if (bin) {
    // The energy vector's peak is coarser than the correlation peak: twice its sigma.
    length = *bin * shift_per_bin;
    length_sigma = 2.0 * alongTrackSigma(measured);
    obs.shift.push_back({length, length_sigma});
  }
  const double direction = measured.direction();
  initial.translation = cv::Point2d(std::cos(direction), std::sin(direction)) * length;
  initial.translation_covariance =
      alongAcrossCovariance(direction, std::max(length_sigma, kMinShiftSigma),
                            std::sqrt(std::max(cv::trace(measured.translation_covariance), 0.0)));
  return obs;
}

}  // namespace

std::optional<Estimate> Estimator::process(FrameSpectra spectra, double stamp, double prepare_ms) {
  const Clock::time_point start = Clock::now();
  State& s = *state_;
  Estimate est;
  est.frame_index = frame_count_++;
  est.stamp = stamp;
  est.mode = config_.mode;
  est.registration_ms = prepare_ms;
  s.last_stamp = stamp;
  WindowFrame frame{std::move(spectra), est.frame_index, stamp};
  const bool textured = frame.spectra.texture >= config_.registration.min_texture &&
                        std::isfinite(frame.spectra.texture);
  const auto finish = [&]() -> std::optional<Estimate> {
    est.pose = s.integrator.pose();
    est.total_ms = prepare_ms + msSince(start);
    est.estimator_ms = std::max(0.0, est.total_ms - est.registration_ms);
    return std::optional<Estimate>(std::move(est));
  };
  const double altitude = s.integrator.altitude();
  const cv::Matx44d held_growth = cv::Matx44d::diag(cv::Vec4d(
      std::pow(kHeldPositionSigma * altitude, 2), std::pow(kHeldPositionSigma * altitude, 2),
      std::pow(kHeldAltitudeSigma * altitude, 2), kHeldYawSigma * kHeldYawSigma));

  // No anchor frame yet: this frame becomes it.
  if (!s.f1) {
    if (!s.started) {
      s.integrator.reset(stamp);
      s.started = true;
      est.state = TrackingState::kStarted;
    } else {
      s.integrator.hold(stamp, held_growth);
      est.state = TrackingState::kHeld;
    }
    if (textured) {
      s.f1 = std::move(frame);
    } else {
      est.degraded = true;
    }
    return finish();
  }

  est.frame_gap = static_cast<int>(frame.index - s.f1->index);
  const RegistrationMethod method =
      config_.mode == EstimatorMode::kFmt ? RegistrationMethod::kClassic : RegistrationMethod::kEnergyVectors;
  Clock::time_point t = Clock::now();
  est.registration12 = s.registrar.registerPair(s.f1->spectra, frame.spectra, method);
  est.registration_ms += msSince(t);

  if (!est.registration12.usable()) {
    // This frame cannot be registered: predict (or hold) and keep the window, or restart it.
    ++s.failed;
    est.degraded = true;
    if (!s.anchor) s.anchor = s.integrator.pose();
    if (config_.tracking.predict_failed_frames && s.last_step &&
        s.failed <= config_.tracking.max_failed_frames) {
      PairMotion predicted = *s.last_step;
      const double spread = config_.tracking.prediction_sigma * predicted.shift();
      predicted.translation_covariance += cv::Matx22d::eye() * (spread * spread + 1.0);
      predicted.rotation_sigma = std::hypot(predicted.rotation_sigma, kPredictedRotationSigma);
      predicted.log_zoom_sigma = std::hypot(predicted.log_zoom_sigma, kPredictedLogZoomSigma);
      s.integrator.integrate(predicted, stamp);
      est.state = TrackingState::kPredicted;
    } else {
      s.integrator.hold(stamp, held_growth);
      est.state = TrackingState::kHeld;
    }
    if (s.failed > config_.tracking.max_failed_frames) {
      // Too long without a registration: restart from this frame, continuing from this pose.
      s.f0.reset();
      s.forgetPair01();
      s.anchor.reset();
      s.last_step.reset();
      s.failed = 0;
      if (textured) {
        s.f1 = std::move(frame);
        est.state = TrackingState::kRestarted;
      } else {
        s.f1.reset();
      }
    }
    return finish();
  }

  const double shift_per_bin = s.registrar.shiftPerBin();
  const double log_zoom_per_bin = s.registrar.logZoomPerBin();
  const PairRegistration& reg12 = est.registration12;
  PairMotion step = calibrated(reg12, config_.uncertainty);
  est.measured12 = step;
  std::vector<float> next_translation01 = reg12.translation_energy;

  if (config_.mode == EstimatorMode::kEfmt) {
    // Multi-zoom translation of the consecutive pair; its length follows the first pair's by PMT.
    t = Clock::now();
    MultiZoomTranslation mz = s.multi_zoom.analyse(s.f1->spectra, frame.spectra, reg12);
    est.registration_ms += msSince(t);
    if (mz.valid) {
      // The unit length (first pair) is the dominant correlation peak's, as in oefmt's start-up;
      // later lengths follow it by PMT (or fall back to the fused profile's peak).
      double length = s.have01 ? refinedArgmax(mz.profile) * shift_per_bin : step.shift();
      double length_sigma = alongTrackSigma(step);
      if (s.have01 && !s.translation01.empty() &&
          s.motion01.shift() >= config_.matching.min_peak_bins * shift_per_bin) {
        t = Clock::now();
        est.pmt12 = matchStretch(s.translation01, mz.profile,
                                 stretchOptions(config_.matching,
                                                double(est.frame_gap) / s.gap01,
                                                config_.matching.stretch_key_12,
                                                s.motion01.shift() / shift_per_bin));
        est.matching_ms = msSince(t);
        if (est.pmt12.valid) {
          length = est.pmt12.value * s.motion01.shift();
          length_sigma = std::hypot(length * est.pmt12.sigma,
                                    est.pmt12.value * alongTrackSigma(s.motion01));
        }
      }
      step.translation = cv::Point2d(std::cos(mz.direction), std::sin(mz.direction)) * length;
      step.translation_covariance = alongAcrossCovariance(
          mz.direction, std::max(length_sigma, kMinShiftSigma),
          std::max(length * mz.direction_sigma * config_.uncertainty.direction_scale, kMinShiftSigma));
      next_translation01 = std::move(mz.profile);
    }
  } else if (config_.mode == EstimatorMode::kOefmt && s.f0 && s.have01) {
    // The three-frame window: pair 0-2, pattern matching, loop optimization.
    t = Clock::now();
    est.registration02 = s.registrar.registerPair(s.f0->spectra, frame.spectra, method);
    est.has_registration02 = true;
    est.registration_ms += msSince(t);
    const PairRegistration& reg02 = est.registration02;
    const int gap12 = est.frame_gap;
    const int gap02 = s.gap01 + gap12;
    Reference ref;
    ref.translation = s.motion01.translation;
    ref.shift = s.motion01.shift();
    ref.shift_sigma = alongTrackSigma(s.motion01);
    ref.raw_log_zoom = s.raw_log_zoom01;
    ref.raw_log_zoom_sigma = s.raw_log_zoom_sigma01;
    const bool usable02 = reg02.usable();
    const bool stretch_ok = !s.translation01.empty() &&
                            ref.shift >= config_.matching.min_peak_bins * shift_per_bin;
    const MatchingConfig& mc = config_.matching;
    t = Clock::now();
    if (stretch_ok) {
      const double reference_bin = ref.shift / shift_per_bin;
      est.pmt12 = matchStretch(
          s.translation01, reg12.translation_energy,
          stretchOptions(mc, double(gap12) / s.gap01, mc.stretch_key_12, reference_bin));
      if (usable02) {
        est.pmt02 = matchStretch(
            s.translation01, reg02.translation_energy,
            stretchOptions(mc, double(gap02) / s.gap01, mc.stretch_key_02, reference_bin));
      }
    }
    if (!s.zoom01.empty()) {
      est.pms12 = matchShift(s.zoom01, reg12.zoom_energy, shiftOptions(mc));
      if (usable02) est.pms02 = matchShift(s.zoom01, reg02.zoom_energy, shiftOptions(mc));
    }
    est.matching_ms = msSince(t);
    PairMotion initial12;
    const PairObservations obs12 =
        observe(reg12, step, est.pmt12, est.pms12, ref, config_, shift_per_bin, log_zoom_per_bin,
                double(gap12) / s.gap01, initial12);
    est.translation_use12 = obs12.translation_use;
    est.measured12 = initial12;
    step = initial12;
    if (usable02) {
      PairMotion initial02;
      const PairObservations obs02 =
          observe(reg02, calibrated(reg02, config_.uncertainty), est.pmt02, est.pms02, ref, config_,
                  shift_per_bin, log_zoom_per_bin, double(gap02) / s.gap01, initial02);
      est.translation_use02 = obs02.translation_use;
      t = Clock::now();
      est.loop = s.optimizer.solve(s.motion01, obs12, obs02, initial12, initial02);
      est.optimizer_ms = msSince(t);
      if (est.loop.status == OptimizerStatus::kConverged) {
        step = est.loop.pair12;
        if (ref.shift > 0.0) est.lambda_t02 = est.loop.pair02.shift() / ref.shift;
      } else {
        est.degraded = true;
      }
    }
  }

  // Integrate, from the anchor if predictions were made while frames failed.
  if (s.anchor) s.integrator.restore(*s.anchor);
  s.integrator.integrate(step, stamp);
  est.step = step;
  est.state = TrackingState::kTracking;
  if (s.have01 && s.motion01.shift() > 0.0) est.lambda_t12 = step.shift() / s.motion01.shift();

  // Slide the window: the integrated 1-2 becomes the next 0-1.
  s.last_step = perInterval(step, est.frame_gap);
  s.motion01 = step;
  s.translation01 = std::move(next_translation01);
  s.zoom01 = reg12.zoom_energy;
  s.raw_log_zoom01 = est.measured12.log_zoom;
  s.raw_log_zoom_sigma01 = est.measured12.log_zoom_sigma;
  s.gap01 = est.frame_gap;
  s.have01 = true;
  s.failed = 0;
  s.anchor.reset();
  s.f0 = std::move(s.f1);
  s.f1 = std::move(frame);
  return finish();
}

}  // namespace oefmt
