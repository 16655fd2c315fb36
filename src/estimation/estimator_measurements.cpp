// SPDX-License-Identifier: GPL-3.0-or-later
#include "estimator_measurements.h"

#include <algorithm>
#include <cmath>
#include <optional>

namespace oefmt {
namespace detail {
namespace {

constexpr double kMinRotationSigma = 1e-5;  // [rad]
constexpr double kMinLogZoomSigma = 1e-5;

double finiteOr(double v, double fallback) { return std::isfinite(v) ? v : fallback; }

// Smallest gate [px] between the followed layer's predicted and measured shift: sub-pixel noise.
constexpr double kMinLayerGatePx = 1.5;
// A peak further than this many of the PMT's sigmas from the length the PMT reads is not the
// layer the PMT read: a normal error stays within three sigmas 99.7 % of the time.
constexpr double kPmtGateSigmas = 3.0;
// How far two depth layers' speed ratios between consecutive pairs may differ [relative]: their
// energy peaks' sub-bin noise, as the layer ratio memory's tolerance.
constexpr double kSpeedRatioTolerance = 0.01;

// `step` at the `length` [px] a depth layer's energy peak gave it: that layer's lower peak is
// less sharp than the correlation peak, twice its sigma along the step.
PairMotion atLayerLength(const PairMotion& step, double length) {
  const double across = std::sqrt(std::max(cv::trace(step.translation_covariance), 0.0));
  return withLength(step, length, std::max(2.0 * alongTrackSigma(step), kMinShiftSigma),
                    std::max(across * length / step.shift(), kMinShiftSigma));
}

// The speed ratio of the depth layer at `bin` of pair 1-2: its shift over the interval against
// the pair 0-1 peak (`peaks01`) nearest to steady speed, within tracking.layer_gate of it; none
// where no peak of pair 0-1 lies that close.
std::optional<double> steadySpeedRatio(double bin, const std::vector<EnergyPeak>& peaks01, double intervals,
                                       double layer_gate) {
  std::optional<double> nearest;
  for (const EnergyPeak& q : peaks01) {
    if (!(q.bin > 0.0)) continue;
    const double r = bin / intervals / q.bin;
    if (std::fabs(r - 1.0) <= layer_gate && (!nearest || std::fabs(r - 1.0) < std::fabs(*nearest - 1.0))) {
      nearest = r;
    }
  }
  return nearest;
}

// Speed ratios of a rigid scene: a change of the vehicle's speed changes every depth layer's
// shift by the same ratio (a climb's zoom adds a little more for the nearer layers). A candidate
// for the followed layer's length, at `candidate_ratio` of the steady length, is another layer (a
// wall, a neighbouring top a few per cent nearer) where at least two other layers seen in both
// pairs (a translation energy peak of pair 1-2 with one of pair 0-1 within tracking.layer_gate of
// it over the frame intervals, both reaching tracking.steady_layer_min_fraction) agree on another
// ratio and none keeps the candidate's. Where walls fill the energy vectors with peaks between
// the layers, one of them inside the gate was taken for the followed layer at each pair, and the
// length walked from one to the next. Returns the ratio the other layers agree on, or nothing
// where the candidate may be the followed layer.
std::optional<double> contradictingSpeedRatio(const std::vector<float>& energy12, const std::vector<float>& energy01,
                                              double candidate_bin, double candidate_ratio, double intervals,
                                              double log_zoom, const TrackingConfig& tracking) {
  if (energy12.empty() || energy01.empty() || !(intervals > 0.0) || !(candidate_ratio > 0.0)) return std::nullopt;
  const double tolerance = kSpeedRatioTolerance + std::fabs(log_zoom);
  // Only layers whose peaks could carry a step testify: walls leave weaker peaks at every length,
  // and some pair of them keeps any ratio.
  const std::vector<EnergyPeak> peaks01 = energyPeaks(energy01, tracking.steady_layer_min_fraction);
  std::vector<double> ratios;  // per other layer of pair 1-2: its speed ratio nearest to steady speed
  for (const EnergyPeak& p : energyPeaks(energy12, tracking.steady_layer_min_fraction)) {
    if (std::fabs(p.bin - candidate_bin) <= 1.0) continue;  // the candidate's own peak
    for (const EnergyPeak& q : peaks01) {
      if (q.bin > 0.0 && std::fabs(p.bin / intervals / q.bin - candidate_ratio) <= tolerance) {
        return std::nullopt;  // a layer keeps the candidate's ratio
      }
    }
    if (const std::optional<double> r = steadySpeedRatio(p.bin, peaks01, intervals, tracking.layer_gate)) {
      ratios.push_back(*r);
    }
  }
  // The largest group of ratios within the tolerance of each other, its median.
  std::sort(ratios.begin(), ratios.end());
  std::size_t best_first = 0, best_count = 0;
  for (std::size_t i = 0; i < ratios.size(); ++i) {
    std::size_t j = i;
    while (j + 1 < ratios.size() && ratios[j + 1] - ratios[i] <= tolerance) ++j;
    if (j - i + 1 > best_count) {
      best_first = i;
      best_count = j - i + 1;
    }
  }
  if (best_count < 2) return std::nullopt;
  return ratios[best_first + best_count / 2];
}

// The followed layer's own peak in pair 1-2's translation energy vector within
// tracking.layer_gate of `length` [px] (the predicted one), down to tracking.layer_min_fraction
// of the vector's maximum, as the step of that length along `measured`; none where the
// measurement lies within the gate already or no such peak is there.
std::optional<PairMotion> followedLayerTrace(const PairMotion& measured, const PairRegistration& registration,
                                             double length, const EstimatorConfig& config, double shift_per_bin) {
  const double gate = config.tracking.layer_gate * length;
  if (!(shift_per_bin > 0.0) || !(measured.shift() > 0.0) || !(std::fabs(measured.shift() - length) > gate)) {
    return std::nullopt;
  }
  const std::optional<double> bin = peakNear(registration.translation_energy, length / shift_per_bin,
                                             gate / shift_per_bin, config.tracking.layer_min_fraction);
  if (!bin) return std::nullopt;
  return atLayerLength(measured, *bin * shift_per_bin);
}

// observe() with a predicted translation: which peak is the followed layer's (see the header).
// Depth layers of one motion lie along one direction at different lengths: the length tells the
// layer; the direction only has to be the motion's (within the acceleration window).
void observeFollowedLayer(const PairRegistration& registration, const PairMotion& measured,
                          const MatchResult& pmt, const Reference& ref, const EstimatorConfig& config,
                          double shift_per_bin, double intervals, const RegistrationPrior& prior,
                          bool skipped_frames, PairObservations& obs, PairMotion& initial) {
  const cv::Point2d predicted = prior.translation;
  const double length = cv::norm(predicted);
  const double gate =
      std::max({config.tracking.layer_gate * length, 3.0 * prior.translation_sigma, kMinLayerGatePx});
  // Distance of a shift from the predicted direction's line, and whether it lies on the motion.
  const auto across = [&](const cv::Point2d& d) {
    return length > 0.0 ? std::fabs(d.x * predicted.y - d.y * predicted.x) / length : cv::norm(d);
  };
  const auto alongMotion = [&](const cv::Point2d& d) {
    return across(d) <= prior.translation_radius && d.dot(predicted) >= 0.0;
  };
  // The gate widens with the motion's spread (a vehicle that changed its speed may change it
  // again), but the energy vectors' stretch (PMT) reads the followed layer's own length: where it
  // does so within the gate, a peak further than tracking.layer_gate from that length is another
  // layer or an alias, however wide the gate. Without this one switch between layers widens the
  // spread of the last steps, and the wider gate lets the next switch through. Neighbouring
  // layers (a sloped roof, tops a few per cent of the altitude apart) lie closer to each other
  // than layer_gate, while the PMT reads the length to a fraction of a per cent: where its own
  // sigma says so, the gate around its length narrows to kPmtGateSigmas of them.
  const double pmt_length = pmt.valid ? pmt.value * ref.shift : 0.0;
  const bool pmt_reads_layer = pmt.valid && std::fabs(pmt_length - length) <= gate;
  const double pmt_sigma = pmt.valid ? std::hypot(pmt_length * pmt.sigma, pmt.value * ref.shift_sigma) : 0.0;
  const double pmt_gate = std::max(std::min(config.tracking.layer_gate * pmt_length, kPmtGateSigmas * pmt_sigma),
                                   kMinLayerGatePx);
  const auto inGate = [&](const cv::Point2d& d) {
    return alongMotion(d) && std::fabs(cv::norm(d) - length) <= gate &&
           (!pmt_reads_layer || std::fabs(cv::norm(d) - pmt_length) <= pmt_gate);
  };
  // Nor is a peak whose speed ratio the other layers seen in both pairs refute: the ratio they
  // agree on gives the followed layer's length.
  const std::vector<float> no_energy;
  const std::vector<float>& energy01 = ref.translation_energy ? *ref.translation_energy : no_energy;
  const auto refutingRatio = [&](const cv::Point2d& d) -> std::optional<double> {
    if (!(length > 0.0) || !(shift_per_bin > 0.0)) return std::nullopt;
    return contradictingSpeedRatio(registration.translation_energy, energy01, cv::norm(d) / shift_per_bin,
                                   cv::norm(d) / length, intervals, prior.log_zoom, config.tracking);
  };
  const auto followed = [&](const cv::Point2d& d) { return inGate(d) && !refutingRatio(d); };
  const bool measured_in_gate = inGate(measured.translation);
  const std::optional<double> refuted = measured_in_gate ? refutingRatio(measured.translation) : std::nullopt;
  obs.length_source = LengthSource::kPeak;
  if (measured_in_gate && !refuted) return;  // the correlation peak is the layer's
  if (registration.followed_confidence >= config.registration.min_confidence &&
      followed(registration.followed_translation)) {
    // Another layer's peak is the highest; the followed one stands out where it was predicted.
    // A lower peak than the correlation's: twice its sigma.
    obs.translation = registration.followed_translation;
    obs.translation_covariance = measured.translation_covariance * 4.0;
    obs.length_source = LengthSource::kWindowPeak;
    initial = measured;
    initial.translation = obs.translation;
    initial.translation_covariance = obs.translation_covariance;
    // The registration's zoom is the highest peak's layer's (its refinement starts at that
    // shift). A climb zooms each layer by the inverse of its depth, as the motion shifts it: where
    // the highest peak is another layer of the motion, the followed layer's zoom is that one's
    // scaled by the two peaks' ratio, both read in this pair, and so is its error. Taken as it
    // is, a climb over roofs reads the roofs' larger zoom wherever their peak is the highest, and
    // the altitude grows by it.
    ScalarObservation& zoom = obs.log_zoom.front();  // fromMotion's: the registration's
    const double layer_ratio = measured.shift() > 0.0 ? cv::norm(obs.translation) / measured.shift() : 0.0;
    if (alongMotion(measured.translation) && layer_ratio >= 1.0 / kMaxDepthLayerRatio &&
        layer_ratio <= kMaxDepthLayerRatio) {
      zoom.value *= layer_ratio;
      zoom.sigma *= layer_ratio;
    } else if (measured.shift() > 0.0) {
      // The highest peak is no layer of the motion (an alias off its direction, or on it further
      // than a layer can be), and the zoom refined at its shift says nothing of the followed
      // layer's: the prediction's zoom stands, with both sigmas. Scaled by such a ratio, an
      // alias's small zoom error became a step of the altitude.
      zoom.value = prior.log_zoom;
      zoom.sigma = std::hypot(zoom.sigma, prior.log_zoom_sigma);
    }
    initial.log_zoom = zoom.value;
    initial.log_zoom_sigma = zoom.sigma;
    return;
  }
  // The followed layer is not in view. A correlation peak along the motion is another layer of
  // it (its direction holds); off it, an alias (nothing of it holds).
  const bool on_direction = measured.shift() > 0.0 && alongMotion(measured.translation);
  // A peak the vehicle can reach, read off a pair over one frame interval only, may be a change
  // of speed where no layer tells the followed one's length.
  const bool speed_change_in_reach = on_direction && !skipped_frames &&
                                     cv::norm(measured.translation - predicted) <= prior.translation_radius;
  LengthSource layered_source = LengthSource::kPrediction;
  // The layers' speeds are compared at the predicted zoom: a pair whose highest peak is another
  // layer's or a wall's may have misread its zoom as well.
  PairMotion at_predicted_zoom = measured;
  at_predicted_zoom.log_zoom = prior.log_zoom;
  PairMotion layered =
      refuted ? atLayerLength(measured, length * *refuted)
              : steadyLayerStep(at_predicted_zoom, registration, energy01, length, config, shift_per_bin,
                                intervals, &layered_source);
  if (refuted) layered_source = LengthSource::kLayerRatio;
  if (layered.translation == measured.translation && speed_change_in_reach) {
    // The peak would be read as a change of speed, the strongest claim one pair can make. Where
    // the followed layer still leaves a trace at the predicted length, too small to carry a step
    // by itself but a depth layer by the energy vector's own measure, the layer is in view and the
    // speed did not change: the peak is another layer's or an alias.
    if (const std::optional<PairMotion> trace = followedLayerTrace(measured, registration, length, config, shift_per_bin)) {
      layered = *trace;
      layered_source = LengthSource::kEnergyPeak;
    }
  }
  // The energy vectors' stretch, where it differs from the peak's: the peak is another layer.
  const bool pmt_says_other_layer =
      pmt.valid && std::fabs(measured.shift() - pmt_length) > gate &&
      std::fabs(pmt_length - length) <= prior.translation_radius;
  if (layered.translation == measured.translation && !pmt_says_other_layer) {
    // No layer tells the followed one's length: the peak is the motion's change (its layer is
    // followed from here).
    if (speed_change_in_reach) {
      obs.length_source = LengthSource::kMotionChange;
      return;
    }
  }
  obs.translation_use = on_direction ? PairObservations::TranslationUse::kDirection
                                     : PairObservations::TranslationUse::kNone;
  double along = length, along_sigma = prior.translation_radius / 3.0;
  obs.length_source = LengthSource::kPrediction;
  if (layered.translation != measured.translation) {
    along = layered.shift();
    along_sigma = alongTrackSigma(layered);
    obs.length_source = layered_source;
  } else if (pmt_says_other_layer || pmt_reads_layer) {
    along = pmt_length;
    along_sigma = pmt_sigma;
    obs.length_source = LengthSource::kStretch;
  }
  along_sigma = std::max(along_sigma, kMinShiftSigma);
  obs.shift.push_back({along, along_sigma});
  const double across_measured = std::sqrt(std::max(cv::trace(measured.translation_covariance), 0.0));
  initial = withLength(measured, along, along_sigma, std::max(along * 0.01, across_measured));
  if (!on_direction) {
    const double direction = std::atan2(predicted.y, predicted.x);
    initial.translation = cv::Point2d(std::cos(direction), std::sin(direction)) * along;
    initial.translation_covariance = alongAcrossCovariance(direction, along_sigma, prior.translation_radius / 3.0);
  }
}

}  // namespace

PairMotion withLength(const PairMotion& motion, double length, double along, double across) {
  PairMotion out = motion;
  const double direction = motion.direction();
  out.translation = cv::Point2d(std::cos(direction), std::sin(direction)) * length;
  out.translation_covariance = alongAcrossCovariance(direction, along, across);
  return out;
}

PairMotion calibrated(const PairRegistration& r, const UncertaintyConfig& u) {
  PairMotion m;
  m.rotation = wrapToPi(finiteOr(r.rotation, 0.0));
  m.log_zoom = r.zoom > 0.0 && std::isfinite(r.zoom) ? std::log(r.zoom) : 0.0;
  m.translation = {finiteOr(r.translation.x, 0.0), finiteOr(r.translation.y, 0.0)};
  // Peak widths become error sigmas; a rotation and zoom taken from the prediction already
  // carry the prediction's error sigmas.
  const bool predicted = r.rotation_zoom_candidate == PairRegistration::kPredicted;
  m.rotation_sigma = std::max(finiteOr(r.rotation_sigma, CV_PI) * (predicted ? 1.0 : u.rotation_scale),
                              kMinRotationSigma);
  m.log_zoom_sigma = std::max(finiteOr(r.log_zoom_sigma, 1.0) * (predicted ? 1.0 : u.log_zoom_scale),
                              kMinLogZoomSigma);
  if (!predicted && r.zoom_refined && r.refined_log_zoom_sigma > 0.0) {
    // The refined zoom's own sigma: the surface's peak width is the same for every pair of a
    // scene (about 1 %), while the refined zooms of the corpus erred 0.02 % to 0.3 %, as the
    // refinement's normal equations say, and as far again as the slope correction that was not
    // taken where a slope or the layers stretch the view (doc/method.md).
    m.log_zoom_sigma = std::max(std::hypot(r.refined_log_zoom_sigma * u.refined_log_zoom_scale, r.slope_log_zoom_sigma),
                                kMinLogZoomSigma);
  }
  if (!predicted && r.zoom_refined && r.refined_rotation_sigma > 0.0 && std::isfinite(r.refined_rotation)) {
    // Two readings of the rotation: the surface's peak, whose fraction of a bin leans towards
    // or away from the whole bin by a few hundredths of a bin (every frame alike in a steady
    // turn, so the heading drifts), and the refinement's (or, where it had not settled, the
    // image blocks'), unbiased on one plane but noisy on weak texture. Each weighs by its error
    // sigma, and the mean has the sigma of both: the loop weighs this pair's rotation against
    // pair 0-2's by it.
    const double surface = m.rotation_sigma;
    const double refined = std::max(r.refined_rotation_sigma * u.refined_rotation_scale, kMinRotationSigma);
    const double weight = surface * surface / (surface * surface + refined * refined);
    m.rotation = wrapToPi(m.rotation + weight * wrapToPi(r.refined_rotation - r.rotation));
    m.rotation_sigma = std::max(surface * refined / std::hypot(surface, refined), kMinRotationSigma);
  }
  const double shift = m.shift();
  const double along = std::max(finiteOr(r.shift_sigma, 1e3) * u.shift_scale, kMinShiftSigma);
  // Below a pixel the direction means little: the along-track sigma holds in every direction.
  const double across = shift >= 1.0
                            ? std::max(shift * finiteOr(r.direction_sigma, CV_PI) * u.direction_scale,
                                       kMinShiftSigma)
                            : along;
  m.translation_covariance = alongAcrossCovariance(m.direction(), along, across);
  // A rival peak as high (a periodic texture's alias, or the motion where the taken peak is the
  // alias) makes the reading one of two: the covariance of that mixture, the rival weighing up
  // to a half as it reaches the taken peak's height.
  const double rival_weight = 0.5 * (1.0 - r.uniqueness());
  if (rival_weight > 0.0) {
    const cv::Vec2d apart(finiteOr(r.rival_translation.x - r.translation.x, 0.0),
                          finiteOr(r.rival_translation.y - r.translation.y, 0.0));
    m.translation_covariance += rival_weight * (1.0 - rival_weight) * (apart * apart.t());
  }
  return m;
}

double alongTrackSigma(const PairMotion& m) {
  const cv::Matx22d& c = m.translation_covariance;
  const double length = m.shift();
  if (!(length > 1e-9)) return std::sqrt(std::max(0.5 * (c(0, 0) + c(1, 1)), 0.0));
  const double ux = m.translation.x / length, uy = m.translation.y / length;
  return std::sqrt(std::max(ux * ux * c(0, 0) + 2.0 * ux * uy * c(0, 1) + uy * uy * c(1, 1), 0.0));
}

double lengthSpread(double length, const std::vector<double>& alternatives, double layer_gate, double window) {
  if (!(length > 0.0) || !std::isfinite(length)) return 0.0;
  double spread = 0.0;
  for (const double alternative : alternatives) {
    if (!(alternative > 0.0) || !std::isfinite(alternative)) continue;
    const double off = std::fabs(alternative - length);
    if (off <= layer_gate * length) continue;
    if (window > 0.0 && off > window) continue;
    spread = std::max(spread, off);
  }
  return spread;
}

bool lengthFromOwnPeak(LengthSource source) {
  return source == LengthSource::kPeak || source == LengthSource::kWindowPeak ||
         source == LengthSource::kMotionChange || source == LengthSource::kLoop;
}

bool vouchedLengthWins(double length, LengthSource source, double vouched, double steady, double layer_gate,
                       double tolerance) {
  if (!(length > 0.0) || !(vouched > 0.0) || !(steady > 0.0)) return false;
  const double step_off = std::fabs(length - steady), vouched_off = std::fabs(vouched - steady);
  // A periodic texture's aliases hold ratios of their own, and the lengths they vouch for jump:
  // never towards a length further from the prediction than the step.
  if (!(vouched_off < step_off)) return false;
  if (std::fabs(length - vouched) > layer_gate * vouched) return true;
  const bool weak = source == LengthSource::kEnergyPeak || source == LengthSource::kLayerRatio;
  return weak && vouched_off <= 2.0 * tolerance * steady && vouched_off + tolerance * steady < step_off;
}

PairMotion withAlongTrackSpread(const PairMotion& motion, double spread) {
  const double length = motion.shift();
  if (!(spread > 0.0) || !(length > 0.0)) return motion;
  PairMotion out = motion;
  out.translation_covariance += alongAcrossCovariance(motion.direction(), spread, 0.0);
  return out;
}

PairMotion perInterval(const PairMotion& m, int gap) {
  if (gap <= 1) return m;
  PairMotion out = m;
  out.rotation /= gap;
  out.log_zoom /= gap;
  out.translation = m.translation * (1.0 / gap);
  out.translation_covariance = m.translation_covariance * (1.0 / (gap * gap));
  return out;
}

PairMotion extrapolatedStep(const PairMotion& last, const std::deque<PairMotion>& rates) {
  PairMotion step = last;
  if (rates.empty()) return step;
  std::vector<double> rotations, log_zooms;
  for (const PairMotion& m : rates) {
    rotations.push_back(m.rotation);
    log_zooms.push_back(m.log_zoom);
  }
  step.rotation = medianOf(std::move(rotations));
  step.log_zoom = medianOf(std::move(log_zooms));
  return step;
}

std::optional<double> steadilyChangingTurn(const std::deque<PairMotion>& rates) {
  if (rates.size() < 3) return std::nullopt;
  const double a = rates[rates.size() - 3].rotation, b = rates[rates.size() - 2].rotation, c = rates.back().rotation;
  const double first = wrapToPi(b - a), second = wrapToPi(c - b);
  if (!(first * second > 0.0)) return std::nullopt;
  const double change = first > 0.0 ? std::min(first, second) : std::max(first, second);
  return wrapToPi(b + 2.0 * change);
}

RateDeviations::RateDeviations(std::size_t frames, std::size_t support, double gate, double floor)
    : frames_(frames), support_(std::min(support, frames)), gate_(gate), floor_(floor) {}

bool RateDeviations::beyondGate(double deviation) const {
  return supported() && std::fabs(deviation) > gate_ * spread();
}
bool RateDeviations::withinGate(double deviation) const {
  return supported() && std::fabs(deviation) <= gate_ * spread();
}
bool RateDeviations::outlier(double deviation, bool may_change_rate) {
  if (!may_change_rate && beyondGate(deviation)) return true;
  if (!last_outlier_ && beyondGate(deviation)) {
    last_outlier_ = true;
    return true;
  }
  last_outlier_ = false;
  deviations_.push_back(std::fabs(deviation));
  while (deviations_.size() > frames_) deviations_.pop_front();
  return false;
}

double RateDeviations::spread() const {
  // The median absolute deviation over that of a normal distribution's sigma.
  if (deviations_.empty()) return floor_;
  return std::max(kMadToSigma * medianOf({deviations_.begin(), deviations_.end()}), floor_);
}

void RateDeviations::clear() {
  deviations_.clear();
  last_outlier_ = false;
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

PairObservations observe(const PairRegistration& registration, const PairMotion& measured,
                         const MatchResult& pmt, const MatchResult& pms, const Reference& ref,
                         const EstimatorConfig& config, double shift_per_bin,
                         double log_zoom_per_bin, double intervals, const RegistrationPrior* prior,
                         PairMotion& initial, bool skipped_frames) {
  PairObservations obs = PairObservations::fromMotion(measured);
  initial = measured;
  const bool predicted_translation = prior != nullptr && prior->translation_radius > 0.0;
  if (config.tracking.motion_prior_sigma > 0.0) {
    // The motion so far continued over this pair's frame intervals.
    const cv::Point2d predicted = predicted_translation ? prior->translation : ref.translation * intervals;
    const double sigma = config.tracking.motion_prior_sigma * cv::norm(predicted) + 1.0;
    obs.translation_priors.push_back({predicted, cv::Matx22d::eye() * (sigma * sigma)});
  }
  if (pms.valid) {
    obs.log_zoom.push_back({ref.raw_log_zoom - pms.value * log_zoom_per_bin,
                            std::hypot(pms.sigma * log_zoom_per_bin, ref.raw_log_zoom_sigma)});
  }
  if (predicted_translation) {
    observeFollowedLayer(registration, measured, pmt, ref, config, shift_per_bin, intervals, *prior,
                         skipped_frames, obs, initial);
    return obs;
  }
  if (!pmt.valid) return obs;
  const double predicted = pmt.value * ref.shift;
  const double predicted_sigma = std::hypot(predicted * pmt.sigma, pmt.value * ref.shift_sigma);
  obs.shift.push_back({predicted, predicted_sigma});
  if (std::fabs(measured.shift() - predicted) <= config.tracking.layer_gate * predicted) return obs;

  obs.translation_use = PairObservations::TranslationUse::kDirection;
  obs.length_source = LengthSource::kStretch;
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
    obs.length_source = LengthSource::kEnergyPeak;
  }
  initial = withLength(measured, length, std::max(length_sigma, kMinShiftSigma),
                       std::sqrt(std::max(cv::trace(measured.translation_covariance), 0.0)));
  return obs;
}

PairMotion steadyLayerStep(const PairMotion& candidate, const PairRegistration& registration12,
                           const std::vector<float>& translation01, double steady,
                           const EstimatorConfig& config, double shift_per_bin, double intervals,
                           LengthSource* source) {
  const TrackingConfig& tracking = config.tracking;
  const double length = candidate.shift();
  if (!(shift_per_bin > 0.0) || !(steady > 4.0 * config.matching.skip_bins * shift_per_bin) ||
      !(length > 0.0) || std::fabs(length - steady) <= tracking.layer_gate * steady) {
    return candidate;
  }
  // The followed layer's own peak, at steady speed within layer_gate.
  const double min_fraction = tracking.steady_layer_min_fraction;
  const std::optional<double> own = peakNear(registration12.translation_energy, steady / shift_per_bin,
                                             tracking.layer_gate * steady / shift_per_bin, min_fraction);
  // Unless the layers seen in both pairs say it is another layer, by the speed they agree on.
  const std::optional<double> contradicted =
      own ? contradictingSpeedRatio(registration12.translation_energy, translation01, *own,
                                    *own * shift_per_bin / steady, intervals, candidate.log_zoom, tracking)
          : std::nullopt;
  double ratio = 0.0;  // the speed ratio the step takes; none where nothing tells it
  if (contradicted) {
    ratio = *contradicted;
  } else if (own) {
    ratio = *own * shift_per_bin / steady;
  } else {
    // The followed layer has left the view. The layers seen in both pairs at steady speed (a
    // translation energy peak of pair 1-2 with one of pair 0-1 within layer_gate of it over the
    // frame intervals) give the speed ratio, which holds for every layer of the rigid scene. Of
    // those, the ratio nearest to steady: a neighbour in depth matched to another layer's peak
    // is further off, and on dense three-level flights the nearest ratio tracked better than the
    // median or the highest layer's.
    const std::vector<EnergyPeak> peaks01 = energyPeaks(translation01, tracking.layer_min_fraction);
    for (const EnergyPeak& p : energyPeaks(registration12.translation_energy, min_fraction)) {
      const std::optional<double> r = steadySpeedRatio(p.bin, peaks01, intervals, tracking.layer_gate);
      if (r && (!(ratio > 0.0) || std::fabs(*r - 1.0) < std::fabs(ratio - 1.0))) ratio = *r;
    }
  }
  if (!(ratio > 0.0)) return candidate;
  if (source != nullptr) *source = own && !contradicted ? LengthSource::kEnergyPeak : LengthSource::kLayerRatio;
  return atLayerLength(candidate, steady * ratio);
}

}  // namespace detail
}  // namespace oefmt
