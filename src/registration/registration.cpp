// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/registration/registration.h"

#include <algorithm>
#include <cmath>
#include <complex>
#include <string>

#include <opencv2/imgproc.hpp>

#include "oefmt/registration/energy_vector.h"
#include "oefmt/registration/plane_tilt.h"
#include "oefmt/error.h"
#include "oefmt/registration/phase_correlation.h"
#include "oefmt/registration/pattern_matching.h"
#include "oefmt/registration/similarity_refinement.h"
#include "oefmt/registration/warp.h"

namespace oefmt {
namespace {

// Peak-to-sidelobe ratios mapped to a 0..1 confidence. The translation surface decides: after
// the warp it only peaks when rotation and zoom were right too; unrelated textures give about
// 15 at N = 512, clean registrations hundreds. The rotation/zoom surface weakens long before
// the registration fails (large shifts change the magnitude spectrum), so it has lower bounds.
constexpr double kTranslationPsrFloor = 20.0;
constexpr double kTranslationPsrGood = 60.0;
constexpr double kRotationZoomPsrFloor = 6.0;
constexpr double kRotationZoomPsrGood = 20.0;

// Rows of the polar unwrap (and of the rotation/zoom surface) that compete for the energy row:
// rows further than 10 from the peak are overruled by the peak row anyway (doc/method.md,
// Energy vectors).
constexpr int kPolarBandHalfWidth = 16;
constexpr int kEnergyRowBand = 12;
// Radius columns either side of the chosen translation peak's that the polar peak is searched in.
constexpr int kPolarPeakHalfCols = 2;

// Half size of the window cleared around a rotation/zoom peak already tried [bins]: wider than
// the log-polar peak, narrower than a quarter turn's distance.
constexpr int kTriedPeakRadius = 6;

// A second peak of the window whose weighted height reaches this share of the first's competes
// with it (both are registered).
constexpr double kCompetingPeak = 0.5;

// Zeroes the (2 radius + 1)^2 window around p, rows and columns cyclic (both wrap on the
// rotation/zoom surface).
void clearAround(cv::Mat1f& surface, const cv::Point& p, int radius) {
  for (int dr = -radius; dr <= radius; ++dr) {
    float* row = surface[((p.y + dr) % surface.rows + surface.rows) % surface.rows];
    for (int dc = -radius; dc <= radius; ++dc) row[((p.x + dc) % surface.cols + surface.cols) % surface.cols] = 0.0f;
  }
}

double wrapAngle(double a) {
  a = std::fmod(a + CV_PI, 2.0 * CV_PI);
  if (a <= 0.0) a += 2.0 * CV_PI;
  return a - CV_PI;
}

// Gaussian widths (rows, columns) of the |.|^3 peak, for the single-peak (classic) method.
cv::Point2d peakWidths(const cv::Mat1f& surface, const SurfacePeak& peak, bool cyclic_cols) {
  constexpr int kRadius = 2;
  float along_rows[2 * kRadius + 1];
  float along_cols[2 * kRadius + 1];
  for (int o = -kRadius; o <= kRadius; ++o) {
    const int r = ((peak.row + o) % surface.rows + surface.rows) % surface.rows;
    int c = peak.col + o;
    float col_value = 0.0f;
    if (cyclic_cols) {
      col_value = surface(peak.row, (c % surface.cols + surface.cols) % surface.cols);
    } else if (c >= 0 && c < surface.cols) {
      col_value = surface(peak.row, c);
    }
    along_rows[o + kRadius] = std::pow(std::fabs(surface(r, peak.col)), 3.0f);
    along_cols[o + kRadius] = std::pow(std::fabs(col_value), 3.0f);
  }
  return {gaussianWidth(along_cols, 2 * kRadius + 1, kRadius + peak.sub_col - peak.col, kRadius, false),
          gaussianWidth(along_rows, 2 * kRadius + 1, kRadius + peak.sub_row - peak.row, kRadius, false)};
}

// The configured block radius and smoothing; the callers set what differs per surface.
EnergyVectorOptions energyVectorOptions(const RegistrationConfig& config) {
  EnergyVectorOptions options;
  options.block_radius = config.block_radius;
  options.smoothing_sigma = config.energy_smoothing_sigma;
  return options;
}

// Gauss-Newton steps of the zoom refinement, and the pixels that take part: about 3 000 on a
// regular grid pin four parameters, a stretch and a photometric gain and bias far below a bin at
// any size. The rotation and zoom start within a bin and land close in one step; the stretch
// starts at zero and needs more: after two steps it is read at about half its size (the pairs'
// zoom errors then follow their stretch at twice the slope plane_tilt.h derives), after four
// whole. Not many more: over several depth layers they go on towards one similarity's compromise
// of all the layers, away from the followed layer's zoom (doc/method.md).
constexpr int kRefinementIterations = 4;
constexpr double kRefinementPixels = 3000.0;
// A refinement that moves the rotation or the zoom by more than this many bins of the log-polar
// surface did not start within its reach (another layer, a repetitive pattern): not taken unless
// it fits clearly better, within the motion's window.
constexpr double kRefinementMaxBins = 2.0;
// A change of the refinement's loss within this many of its standard errors is the pixels' noise.
constexpr double kLossEvidence = 2.0;
// A refinement whose last step turned the image's edge (N/2 from the centre) by more than this
// many pixels had not settled: a fiftieth of a pixel is below what the images' interpolation can
// tell, and where one layer fits, the fourth step moves it far less.
constexpr double kSettledEdgeShift = 0.02;
// A sigma of the blocks' rotation (BlockMotion) in sigmas of a settled refinement's, the unit that
// uncertainty.refined_rotation_scale calibrates: on the calibration flights of
// scripts/calibrate_refined_sigmas.py 90 % of the blocks' errors lie within 4.3 of their sigmas
// (45 pairs) and 90 % of the settled refinement's within 3.5 of its, hence 0.6 x 4.3 / 3.5.
constexpr double kBlockSigmaInRefinementSigmas = 0.74;
// otherLayerShifts: how many peaks, and how near the followed shift a peak is the same layer.
constexpr int kOtherLayers = 4;
constexpr double kSameLayerPx = 3.0;

}  // namespace

bool RegistrationPrior::contains(double rotation_rad, double log_zoom_value) const {
  return std::fabs(wrapAngle(rotation_rad - rotation)) <= rotation_window &&
         std::fabs(log_zoom_value - log_zoom) <= log_zoom_window;
}

std::vector<cv::Point2d> otherLayerShifts(const PairRegistration& registration, double shift_per_bin) {
  std::vector<cv::Point2d> shifts;
  const cv::Point2d along(std::cos(registration.direction), std::sin(registration.direction));
  for (const EnergyPeak& peak : energyPeaks(registration.translation_energy, 0.0)) {
    const double shift = peak.bin * shift_per_bin;
    if (std::fabs(shift - registration.shift) <= kSameLayerPx) continue;
    shifts.push_back(along * shift);
    if (static_cast<int>(shifts.size()) == kOtherLayers) break;
  }
  return shifts;
}

namespace {

// The slope correction of a level camera's zoom (logZoomOfSlope), taken only as far as it brings
// the zoom back towards what the motion so far predicts: a slope under the motion explains a
// zoom that broke away from the prediction. Where a stretch would move the zoom away from it,
// or past it, it is not taken as a slope's (occlusions at walls, a mixture of layers that the
// affine model does not describe, noise): over strong parallax the pairs' zoom errors do not
// follow their stretch. Without a prediction nothing is corrected. The part not taken may still
// be a slope's: it is the zoom's uncertainty (PairRegistration::slope_log_zoom_sigma).
double slopeTowardsPrediction(double correction, double to_prediction) {
  if (!(correction * to_prediction > 0.0)) return 0.0;
  return correction > 0.0 ? std::min(correction, to_prediction) : std::max(correction, to_prediction);
}

// The log-polar surface reads a sub-bin zoom (and rotation) towards the nearest bin: at most
// radii its samples are as coarse as the grain of the magnitude spectrum, so a fraction of a bin
// does not move them as a whole. The intensities of both frames tell the rest (doc/method.md).
// The rotation is refined along with the zoom, which it would otherwise bias, but not taken as
// it is: where the scene holds several depths or inclined planes, the rotation that fits the most
// pixels differs from the followed layer's by a fraction of a bin. It is reported with its sigma
// beside the surface's, and the estimator weighs the two (doc/method.md).
void refineZoom(const FrameSpectra& older, const FrameSpectra& newer, const SpectralContext& context,
                double log_zoom_per_bin, const std::optional<cv::Point2d>& plane_tilt,
                const RegistrationPrior* prior, BlockMotionReader* blocks, PairRegistration& result) {
  if (older.refinement.empty() || newer.refinement.empty()) return;
  const int n = context.size();
  ImageSimilarity start;
  start.rotation = result.rotation;
  start.log_zoom = std::log(result.zoom);
  start.translation = result.translation;
  const int stride = std::max(1, static_cast<int>(std::lround(n / std::sqrt(kRefinementPixels))));
  const SimilarityRefinement refined = refineSimilarity(older.refinement, newer.refinement, start,
                                                        context.window().taper(), kRefinementIterations, stride,
                                                        /*fit_stretch=*/true,
                                                        otherLayerShifts(result, context.polarRadiusStep()));
  const double rotation_bins = std::fabs(refined.similarity.rotation - start.rotation) * n / CV_PI;
  const double zoom_bins = std::fabs(refined.similarity.log_zoom - start.log_zoom) / log_zoom_per_bin;
  // The steps went astray when the fit got worse beyond its noise.
  const double loss_noise = kLossEvidence * refined.loss_change_sigma;
  if (!(refined.loss_end >= 0.0) || !(refined.loss_change <= loss_noise)) return;
  if (!(rotation_bins <= kRefinementMaxBins) || !(zoom_bins <= kRefinementMaxBins)) {
    // Weak texture leaves the surface's highest peak a few bins off at times; a refinement that
    // fits clearly better and lands where the motion so far allows corrects it.
    const bool clearly_better = refined.loss_change < -loss_noise;
    if (!clearly_better || prior == nullptr ||
        !prior->contains(refined.similarity.rotation, refined.similarity.log_zoom)) {
      return;
    }
  }
  // A levelled view's stretch is mostly its attitude source's error (a tilt of the whole view,
  // tracked over many pairs); a level camera's, the slope of the surface under this pair.
  if (plane_tilt) {
    result.tilt_log_zoom = logZoomOfTilt(*plane_tilt, refined.similarity.translation);
  } else {
    const double slope =
        logZoomOfSlope(refined.similarity.stretch_a, refined.similarity.stretch_b, refined.similarity.translation);
    if (prior != nullptr) {
      result.tilt_log_zoom = slopeTowardsPrediction(slope, prior->log_zoom - refined.similarity.log_zoom);
    }
    result.slope_log_zoom_sigma = std::fabs(slope - result.tilt_log_zoom);
  }
  result.zoom = std::exp(refined.similarity.log_zoom + result.tilt_log_zoom);
  result.zoom_refined = true;
  result.refined_log_zoom_sigma = refined.log_zoom_sigma;
  // An unsettled refinement was still on its way when it stopped: towards several layers'
  // compromise (walls in view, whose shift grows with their height), or along the valley of a
  // striped texture, where a turn and a zoom together slide the stripes along themselves. Its
  // normal equations pin the rotation as tightly all the same, and where it stops depends on
  // the layers in view: its error is a bias, not noise that a weighted mean would average out.
  // The blocks that follow the pair's shift read the turn instead, across the motion where
  // depth layers pull (block_motion.h); the unsettled steps' stretch is no evidence and is not
  // reported. The zoom stays the refinement's: the blocks' zoom, taken as well, lowered the
  // corpus's worst drift further but turned a periodic tiles flight onto another layer
  // (doc/method.md). A levelled view keeps the refinement's reading, whose stretch tells its
  // attitude source's error (below).
  const double edge = 0.5 * n;
  const bool settled = std::fabs(refined.last_rotation_step) * edge <= kSettledEdgeShift;
  if (!settled && !plane_tilt && blocks != nullptr) {
    ImageSimilarity at = refined.similarity;
    at.stretch_a = at.stretch_b = 0.0;
    const BlockMotion motion = blocks->read(older.grey, newer.grey, at);
    if (motion.valid && motion.rotation_sigma > 0.0) {
      result.motion_blocks = motion.blocks;
      result.refined_rotation = motion.rotation;
      result.refined_rotation_sigma = kBlockSigmaInRefinementSigmas * motion.rotation_sigma;
      return;
    }
  }
  result.stretch_a = refined.similarity.stretch_a;
  result.stretch_b = refined.similarity.stretch_b;
  // A refinement that did not lower the loss still reads the sub-bin zoom the surface cannot,
  // but its rotation is then no evidence beside the surface's.
  if (!(refined.loss_change < 0.0)) return;
  result.refined_rotation = refined.similarity.rotation;
  result.refined_rotation_sigma = refined.rotation_sigma;
  if (plane_tilt) {
    // A levelled view off by its attitude source's error reads the turn off by the rank-one
    // term's antisymmetric part, which the fitted stretch tells (plane_tilt.h): the rotation and
    // stretch read together are the turn, with the sigma of that combination.
    const cv::Point2d d = refined.similarity.translation;
    result.refined_rotation += rotationOfSlope(refined.similarity.stretch_a, refined.similarity.stretch_b, d);
    const cv::Vec3d gradient(1.0, rotationOfSlope(1.0, 0.0, d), rotationOfSlope(0.0, 1.0, d));
    const double variance = (gradient.t() * refined.rotation_stretch_covariance * gradient)(0);
    if (variance > 0.0) result.refined_rotation_sigma = std::sqrt(variance);
  }
}

double confidenceFrom(double psr, double floor, double good) {
  return std::clamp((psr - floor) / (good - floor), 0.0, 1.0);
}

}  // namespace

Registrar::Registrar(const RegistrationConfig& config)
    : Registrar(std::make_shared<const SpectralContext>(config)) {}

Registrar::Registrar(std::shared_ptr<const SpectralContext> context)
    : context_(std::move(context)),
      builder_(context_),
      rotation_zoom_candidates_(context_->config().rotation_zoom_candidates) {
  if (context_->size() >= BlockMotionReader::kMinImageSize) {
    blocks_.emplace(context_->size(), context_->config().fft_planning);
  }
}

FrameSpectra Registrar::analyse(const cv::Mat& image, ChannelOrder order) {
  return builder_.build(image, order);
}

FrameSpectra Registrar::analyse(const PreparedImage& image) { return builder_.build(image); }

double Registrar::logZoomPerBin() const { return std::log(context_->logPolarBase()); }

PairRegistration Registrar::registerPair(const FrameSpectra& older, const FrameSpectra& newer,
                                         RegistrationMethod method,
                                         RegistrationSurfaces* surfaces,
                                         const RegistrationPrior* prior, double max_rotation) {
  const int n = context_->size();
  if (older.empty() || newer.empty()) throw InputError("registerPair: a frame is empty");
  max_rotation_ = max_rotation > 0.0 ? max_rotation : CV_PI;  // NaN: unbounded
  surface_pair_ = {0, 0};
  if (older.grey.rows != n || newer.grey.rows != n || older.spectrum.size() != newer.spectrum.size()) {
    throw InputError("registerPair: frames were analysed at a different size than " +
                     std::to_string(n));
  }
  PairRegistration result;
  const double min_texture = context_->config().min_texture;
  if (!(older.texture >= min_texture) || !(newer.texture >= min_texture)) {
    // Nothing to correlate: report the prior (no motion) with uninformative sigmas.
    result.status = RegistrationStatus::kTextureless;
    result.rotation_sigma = CV_PI;
    result.log_zoom_sigma = 1.0;
    result.direction_sigma = CV_PI;
    result.shift_sigma = n;
    return result;
  }
  correlateRotationZoom(older, newer);
  if (prior != nullptr) {
    result = registerInWindow(older, newer, method, *prior, surfaces);
  } else {
    // A lattice of blocks or a repetitive texture can give a wrong rotation/zoom peak (a quarter
    // turn, a wrong zoom) the highest value; the translation surface then shows no peak. The
    // next highest peaks are tried until one registers: the surface is computed once, and each
    // candidate clears the window around the one before.
    SurfacePeak peak = rotation_zoom_highest_;
    for (int attempt = 0; attempt < rotation_zoom_candidates_; ++attempt) {
      if (attempt > 0) {
        clearAround(rotation_zoom_surface_, cv::Point(peak.col, peak.row), kTriedPeakRadius);
        peak = findPeak(rotation_zoom_surface_, true, nullptr, PeakShape::kBroadened);
      }
      PairRegistration trial;
      RegistrationSurfaces trial_surfaces;
      registerOnce(older, newer, method, trial, peak, surfaces ? &trial_surfaces : nullptr, nullptr);
      if (attempt == 0 || trial.peak_confidence > result.peak_confidence) {
        result = std::move(trial);
        result.rotation_zoom_candidate = attempt;
        if (surfaces != nullptr) *surfaces = std::move(trial_surfaces);
      }
      if (result.status == RegistrationStatus::kOk) break;
    }
  }
  if (prior != nullptr && result.status != RegistrationStatus::kOk) {
    PairRegistration trial;
    RegistrationSurfaces trial_surfaces;
    registerOnPrior(older, newer, method, *prior, trial, surfaces ? &trial_surfaces : nullptr);
    if (trial.peak_confidence > result.peak_confidence) {
      result = std::move(trial);
      if (surfaces != nullptr) *surfaces = std::move(trial_surfaces);
    } else if (prior->rotation_zoom_alone && trial.status != RegistrationStatus::kOk) {
      refineRotationZoomAlone(older, newer, *prior, result);
    }
  }
  return result;
}

void Registrar::refineRotationZoomAlone(const FrameSpectra& older, const FrameSpectra& newer,
                                        const RegistrationPrior& prior, PairRegistration& result) {
  if (!context_->config().refine_zoom || !(prior.translation_radius > 0.0) ||
      !(result.rotation_zoom_confidence >= context_->config().min_confidence)) {
    return;
  }
  // The refinement starts from the translation the motion so far predicts unless the measured
  // one lies in its window: the highest peak elsewhere is an alias or another pair's match, and
  // the intensities pull the similarity only within a few pixels of where it starts.
  const cv::Point2d measured = result.translation;
  if (!(cv::norm(measured - prior.translation) <= prior.translation_radius)) result.translation = prior.translation;
  refineZoom(older, newer, *context_, logZoomPerBin(), plane_tilt_, &prior,
             blocks_ && block_reading_ ? &*blocks_ : nullptr, result);
  result.rotation_zoom_only = result.zoom_refined;
  result.translation = measured;
}

cv::Point2d Registrar::windowCentre(const RegistrationPrior& window) const {
  // Rows: theta = (row - N/2) pi / N, modulo pi (the half turn is decided later); columns:
  // ln s = -(col - N/2) ln b.
  const int n = context_->size();
  return {n / 2 - window.log_zoom / logZoomPerBin(), n / 2 + window.rotation * n / CV_PI};
}

SurfacePeak Registrar::windowPeak(const RegistrationPrior& window, cv::Point exclude) const {
  const int n = context_->size();
  const double log_zoom_per_bin = logZoomPerBin();
  const cv::Point2d centre = windowCentre(window);
  const int half_rows = static_cast<int>(std::ceil(window.rotation_window * n / CV_PI));
  const int half_cols = static_cast<int>(std::ceil(window.log_zoom_window / log_zoom_per_bin));
  const cv::Point2d sigma(window.log_zoom_spread / log_zoom_per_bin, window.rotation_spread * n / CV_PI);
  return findPeakInWindow(rotation_zoom_surface_,
                          cv::Point(static_cast<int>(std::lround(centre.x)), static_cast<int>(std::lround(centre.y))),
                          half_rows, half_cols, true, PeakShape::kBroadened, sigma, exclude);
}

double Registrar::windowWeight(const RegistrationPrior& window, cv::Point peak) const {
  const int n = context_->size();
  const cv::Point2d centre = windowCentre(window);
  const double sigma_cols = window.log_zoom_spread / logZoomPerBin();
  const double sigma_rows = window.rotation_spread * n / CV_PI;
  if (!(sigma_cols > 0.0 && sigma_rows > 0.0)) return 1.0;
  // Rows wrap (the surface spans a half turn), columns too (circular correlation).
  const double dr = std::remainder(peak.y - centre.y, static_cast<double>(n));
  const double dc = std::remainder(peak.x - centre.x, static_cast<double>(n));
  return std::exp(-0.5 * (dc * dc / (sigma_cols * sigma_cols) + dr * dr / (sigma_rows * sigma_rows)));
}

PairRegistration Registrar::registerInWindow(const FrameSpectra& older, const FrameSpectra& newer,
                                            RegistrationMethod method, const RegistrationPrior& prior,
                                            RegistrationSurfaces* surfaces) {
  PairRegistration result;
  const SurfacePeak first = windowPeak(prior);
  registerOnce(older, newer, method, result, first, surfaces, &prior);
  // The next peak of the window: tried when the first did not register, and when it competes
  // with it. Two peaks that both register: one surface of the scene turned and scaled as the
  // prediction expects, the other an inclined plane, whose perspective reads as a turn and a
  // zoom. The one whose translation peak stands out where the followed layer was predicted wins.
  const SurfacePeak second = windowPeak(prior, cv::Point(first.col, first.row));
  if (!(second.value > 0.0f)) return result;
  const double first_score = first.value * windowWeight(prior, cv::Point(first.col, first.row));
  const double second_score = second.value * windowWeight(prior, cv::Point(second.col, second.row));
  const bool registered = result.status == RegistrationStatus::kOk;
  if (registered && !(prior.translation_radius > 0.0 && second_score >= kCompetingPeak * first_score)) {
    return result;
  }
  PairRegistration trial;
  RegistrationSurfaces trial_surfaces;
  registerOnce(older, newer, method, trial, second, surfaces ? &trial_surfaces : nullptr, &prior);
  const bool better = registered ? trial.status == RegistrationStatus::kOk &&
                                       trial.followed_confidence > result.followed_confidence
                                 : trial.peak_confidence > result.peak_confidence;
  if (better) {
    result = std::move(trial);
    result.rotation_zoom_candidate = 1;
    if (surfaces != nullptr) *surfaces = std::move(trial_surfaces);
  }
  return result;
}

void Registrar::registerOnce(const FrameSpectra& older, const FrameSpectra& newer,
                             RegistrationMethod method, PairRegistration& result,
                             const SurfacePeak& rotation_zoom_peak, RegistrationSurfaces* surfaces,
                             const RegistrationPrior* prior) {
  const int n = context_->size();
  const double psr_rotation_zoom = registerRotationZoom(method, result, rotation_zoom_peak);
  if (surfaces != nullptr) surfaces->rotation_zoom = rotation_zoom_surface_.clone();
  const double translation_confidence =
      registerTranslation(older, newer, method, result, true, prior);
  // A levelled view off by its attitude source's error reads a small turn as it moves
  // (plane_tilt.h): the tilt the estimator tracks takes it out, as it does the zoom's.
  if (plane_tilt_) {
    result.rotation += rotationOfTilt(*plane_tilt_, result.translation);
    if (std::fabs(result.rotation) > CV_PI) result.rotation = wrapAngle(result.rotation);
  }
  if (surfaces != nullptr) {
    surfaces->translation = surface_.clone();
    surfaces->translation_polar =
        method == RegistrationMethod::kEnergyVectors ? polar_.clone() : cv::Mat1f();
    surfaces->translation_polar_first_row = ((polar_first_row_ % n) + n) % n;
  }
  result.rotation_zoom_confidence = confidenceFrom(psr_rotation_zoom, kRotationZoomPsrFloor, kRotationZoomPsrGood);
  result.peak_confidence = std::min(result.rotation_zoom_confidence, translation_confidence);
  // A rotation beyond the vehicle's reach, or a rotation or zoom the motion so far rules out
  // (another peak of the whole surface, a half turn the low-resolution test chose), is not
  // taken, however well its translation matched: a repetitive pattern matches itself turned by
  // a quarter, or scaled by its period.
  if (std::fabs(result.rotation) > max_rotation_ ||
      (prior != nullptr && !prior->contains(result.rotation, std::log(result.zoom)))) {
    result.rotation_zoom_implausible = true;
    result.rotation_zoom_confidence = 0.0;
    result.peak_confidence = 0.0;
  }
  result.confidence = result.peak_confidence * result.uniqueness();
  result.status = result.peak_confidence >= context_->config().min_confidence
                      ? RegistrationStatus::kOk
                      : RegistrationStatus::kLowConfidence;
  if (result.status == RegistrationStatus::kOk && context_->config().refine_zoom) {
    refineZoom(older, newer, *context_, logZoomPerBin(), plane_tilt_, prior,
               blocks_ && block_reading_ ? &*blocks_ : nullptr, result);
  }
}

void Registrar::registerOnPrior(const FrameSpectra& older, const FrameSpectra& newer,
                                RegistrationMethod method, const RegistrationPrior& prior,
                                PairRegistration& result, RegistrationSurfaces* surfaces) {
  const int n = context_->size();
  const double log_zoom_per_bin = logZoomPerBin();
  result.rotation = wrapAngle(prior.rotation);
  result.zoom = std::exp(prior.log_zoom);
  result.rotation_sigma = prior.rotation_sigma;
  result.log_zoom_sigma = prior.log_zoom_sigma;
  result.rotation_zoom_candidate = PairRegistration::kPredicted;
  if (method == RegistrationMethod::kEnergyVectors) {
    // The zoom energy vector at the predicted row, for the pattern matching of later pairs.
    SurfacePeak at;
    at.sub_row = n / 2 + prior.rotation * n / CV_PI;
    at.sub_col = n / 2 - prior.log_zoom / log_zoom_per_bin;
    at.row = ((static_cast<int>(std::lround(at.sub_row)) % n) + n) % n;
    at.col = ((static_cast<int>(std::lround(at.sub_col)) % n) + n) % n;
    at.value = rotation_zoom_surface_(at.row, at.col);
    EnergyVectorOptions options = energyVectorOptions(context_->config());
    options.cyclic_cols = true;
    options.row_band = kEnergyRowBand;
    result.zoom_energy = extractEnergyVector(rotation_zoom_surface_, at, options).values;
  }
  if (surfaces != nullptr) surfaces->rotation_zoom = rotation_zoom_surface_.clone();
  // The prediction's rotation is not taken modulo a half turn: no half-turn test.
  const double translation_confidence = registerTranslation(older, newer, method, result, false, &prior);
  if (surfaces != nullptr) {
    surfaces->translation = surface_.clone();
    surfaces->translation_polar =
        method == RegistrationMethod::kEnergyVectors ? polar_.clone() : cv::Mat1f();
    surfaces->translation_polar_first_row = ((polar_first_row_ % n) + n) % n;
  }
  // Nothing was measured of the rotation and zoom: the translation alone says whether they fit.
  result.peak_confidence = translation_confidence;
  result.confidence = result.peak_confidence * result.uniqueness();
  result.status = result.peak_confidence >= context_->config().min_confidence
                      ? RegistrationStatus::kOk
                      : RegistrationStatus::kLowConfidence;
}

void Registrar::correlateRotationZoom(const FrameSpectra& older, const FrameSpectra& newer) {
  // Computed ahead where the builder of both frames did (SpectraBuilder::correlateWithRecent),
  // unless it is not of this context's transforms (a caller's own FrameSpectra): copied, since
  // the candidates clear the surface around the peaks they tried.
  const Fft2d& fft = context_->fft();
  const auto ahead = std::find_if(newer.correlated.begin(), newer.correlated.end(),
                                  [&](const RotationZoomCorrelation& c) {
                                    return older.serial != 0 && c.older_serial == older.serial &&
                                           c.power.rows == fft.size() && c.power.cols == fft.spectrumCols() &&
                                           c.power.isContinuous();
                                  });
  if (ahead != newer.correlated.end()) {
    ahead->power.copyTo(rotation_zoom_power_);
    rotation_zoom_highest_ = ahead->highest;
    rotation_zoom_stats_ = ahead->stats;
  } else {
    // The full surface: a coarse low-resolution search for the rotation row (to invert only a
    // band of rows) picked wrong rows on simulated flights, where much of the log-polar
    // correlation's energy sits at high frequencies. In place: the surface is a view of
    // rotation_zoom_power_ (its own buffer, so that the translation leaves it for the next
    // candidate).
    RotationZoomCorrelation here;
    here.power = rotation_zoom_power_;  // the buffer is reused
    oefmt::correlateRotationZoom(*context_, newer.log_polar_spectrum, older.log_polar_spectrum, here);
    rotation_zoom_power_ = here.power;
    rotation_zoom_highest_ = here.highest;
    rotation_zoom_stats_ = here.stats;
  }
  rotation_zoom_surface_ = fft.realView(rotation_zoom_power_);
}

double Registrar::registerRotationZoom(RegistrationMethod method, PairRegistration& result,
                                       const SurfacePeak& peak) {
  const int n = context_->size();
  const cv::Mat1f& surface = rotation_zoom_surface_;
  const double log_zoom_per_bin = logZoomPerBin();
  // Rows span pi: theta = (row - N/2) pi / N; columns: ln s = -(col - N/2) ln b (doc/method.md).
  result.rotation = (peak.sub_row - n / 2) * CV_PI / n;
  result.zoom = std::exp(-(peak.sub_col - n / 2) * log_zoom_per_bin);
  result.rotation_zoom_peak = peak.value;
  if (method == RegistrationMethod::kEnergyVectors) {
    // Log-zoom columns wrap (circular correlation); only rows near the peak can win.
    EnergyVectorOptions options = energyVectorOptions(context_->config());
    options.cyclic_cols = true;
    options.row_band = kEnergyRowBand;
    EnergyVector zoom_vector = extractEnergyVector(surface, peak, options);
    result.rotation_sigma = zoom_vector.row_sigma * CV_PI / n;
    result.log_zoom_sigma = zoom_vector.col_sigma * log_zoom_per_bin;
    result.zoom_energy = std::move(zoom_vector.values);
  } else {
    const cv::Point2d widths = peakWidths(surface, peak, true);
    result.rotation_sigma = widths.y * CV_PI / n;
    result.log_zoom_sigma = widths.x * log_zoom_per_bin;
  }
  return peakToSidelobeRatio(surface, peak, rotation_zoom_stats_);
}

void Registrar::warpOlder(const FrameSpectra& older, PairRegistration& result) {
  // Bring the older frame onto the newer one's rotation and zoom. Unless that moves no pixel
  // noticeably: then the older frame's own spectrum (the same apodized, mean-free image) serves,
  // and the warp and its FFT are saved.
  const int n = context_->size();
  const double corner = std::sqrt(0.5) * n;
  const double moved = corner * std::abs(std::polar(result.zoom, result.rotation) - 1.0);
  result.warped = !(moved <= context_->config().identity_warp_px);
  if (result.warped) {
    const Fft2d& fft = context_->fft();
    cv::Mat1f warped = fft.inPlaceInput(warped_spectrum_);
    warpSimilarityWindowed(older.grey, result.rotation, result.zoom, context_->window(), warped,
                           older.mean);
    fft.forwardInPlace(warped_spectrum_);
  }
}

double Registrar::registerTranslation(const FrameSpectra& older, const FrameSpectra& newer,
                                      RegistrationMethod method, PairRegistration& result,
                                      bool test_half_turn, const RegistrationPrior* prior) {
  const int n = context_->size();
  // The surface reads the rotation modulo a half turn. The prediction says which; or the
  // vehicle cannot have turned by a quarter turn, and the smaller of the two holds (the
  // surface's rotation lies within a quarter turn of zero).
  const bool resolve = test_half_turn && context_->config().resolve_half_turn;
  if (resolve && prior != nullptr) {
    if (std::fabs(wrapAngle(result.rotation - prior->rotation)) > CV_PI / 2.0) {
      result.half_turn = true;
      result.rotation = wrapAngle(result.rotation + CV_PI);
    }
  } else if (resolve && max_rotation_ < CV_PI / 2.0) {
    result.half_turn = false;
  }
  warpOlder(older, result);
  if (resolve && prior == nullptr && !(max_rotation_ < CV_PI / 2.0)) {
    // A half turn about the FFT's origin conjugates the spectrum of a real image, so the theta + pi
    // hypothesis is tested without a second warp, by a low-resolution correlation. That half
    // turn is about pixel (N/2, N/2), not about the image centre the motion is given about: the
    // winner is warped by its own rotation.
    const cv::Mat2f& warped = result.warped ? warped_spectrum_ : older.spectrum;
    const double same = lowResolutionPeak(newer.spectrum, warped, false, context_->smallFft(),
                                          small_spectrum_, small_surface_);
    const double turned = lowResolutionPeak(newer.spectrum, warped, true, context_->smallFft(),
                                            small_spectrum_, small_surface_);
    if (turned > same) {
      result.half_turn = true;
      result.rotation = wrapAngle(result.rotation + CV_PI);
      warpOlder(older, result);
    }
  }
  const cv::Mat2f& older_spectrum = result.warped ? warped_spectrum_ : older.spectrum;

  // The older frame's noise power also stands for its warp (whose bilinear resampling lowers the
  // noise at high frequencies a little: those are weighted down a little more).
  const float older_noise = context_->config().noise_weighting ? older.noise_power : 0.0f;
  const Fft2d& fft = context_->fft();
  centredCrossPower(newer.spectrum, older_spectrum, cross_power_, false,
                    SimdKernel::kAuto, newer.noise_power, older_noise);
  fft.inverseInPlace(cross_power_);
  surface_ = fft.realView(cross_power_);
  surface_pair_ = {older.serial, newer.serial};
  SurfacePeak peak;
  const double confidence = chooseTranslationPeak(prior, peak, result);
  result.translation = cv::Point2d(peak.sub_col - n / 2, peak.sub_row - n / 2);
  result.direction = std::atan2(result.translation.y, result.translation.x);
  result.shift = std::hypot(result.translation.x, result.translation.y);
  result.translation_peak = peak.value;

  if (method == RegistrationMethod::kEnergyVectors) {
    // Polar unwrap: the depths of the scene lie along one direction at different radii.
    // Only a band of direction rows around the peak's direction can win (see row_band).
    const int band = kPolarBandHalfWidth;
    const int centre_row = static_cast<int>(std::lround(result.direction * n / (2.0 * CV_PI)));
    polar_first_row_ = centre_row - band;
    context_->polarRows(surface_, polar_first_row_, 2 * band + 1, polar_);
    // The energy vector is read along the chosen peak's own direction: the polar surface's
    // highest value may be another one (a periodic texture's alias near the origin, which every
    // direction row passes through).
    const double radius_step = context_->polarRadiusStep();
    const SurfacePeak polar_peak =
        findPeakInWindow(polar_, cv::Point(static_cast<int>(std::lround(result.shift / radius_step)), band),
                         band, kPolarPeakHalfCols, false);
    // Radius columns do not wrap; the rho ~ 0 column is suppressed (see energy_vector.cpp).
    EnergyVectorOptions options = energyVectorOptions(context_->config());
    options.cyclic_cols = false;
    options.suppress_low_cols = true;
    EnergyVector shift_vector = extractEnergyVector(polar_, polar_peak, options);
    result.direction_sigma = shift_vector.row_sigma * 2.0 * CV_PI / n;
    result.shift_sigma = shift_vector.col_sigma * radius_step;
    result.translation_energy = std::move(shift_vector.values);
  } else {
    const cv::Point2d widths = peakWidths(surface_, peak, true);
    result.shift_sigma = std::max(widths.x, widths.y);
    result.direction_sigma = std::min(CV_PI, result.shift_sigma / std::max(result.shift, 1e-9));
  }
  return confidence;
}

std::vector<float> Registrar::translationEnergyAlong(const FrameSpectra& older, const FrameSpectra& newer,
                                                    double direction, double length) {
  const int n = context_->size();
  if (surface_.empty() || !std::isfinite(direction) || older.serial == 0 ||
      surface_pair_ != std::make_pair(older.serial, newer.serial)) {
    return {};
  }
  const int band = kPolarBandHalfWidth;
  const int centre_row = static_cast<int>(std::lround(direction * n / (2.0 * CV_PI)));
  cv::Mat1f polar;
  context_->polarRows(surface_, centre_row - band, 2 * band + 1, polar);
  const double radius_step = context_->polarRadiusStep();
  SurfacePeak peak;
  peak.row = band;
  peak.col = std::clamp(static_cast<int>(std::lround(length / radius_step)), 0, polar.cols - 1);
  peak.value = polar(peak.row, peak.col);
  peak.sub_row = peak.row;
  peak.sub_col = peak.col;
  EnergyVectorOptions options = energyVectorOptions(context_->config());
  options.cyclic_cols = false;
  options.suppress_low_cols = true;
  options.row_band = 4;
  return extractEnergyVector(polar, peak, options).values;
}

double Registrar::chooseTranslationPeak(const RegistrationPrior* prior, SurfacePeak& peak,
                                        PairRegistration& result) {
  const int n = context_->size();
  // The noise weights smooth the peak: its sub-pixel position is a Gaussian's.
  const PeakShape shape = context_->config().noise_weighting ? PeakShape::kGaussian : PeakShape::kDirichlet;
  SurfaceStats stats;
  peak = findPeak(surface_, true, &stats, shape);
  const double global = confidenceFrom(peakToSidelobeRatio(surface_, peak, stats),
                                       kTranslationPsrFloor, kTranslationPsrGood);
  result.translation_from_window = false;
  result.translation_implausible = false;
  result.followed_confidence = 0.0;
  result.rival_ratio = 0.0;
  const double count = static_cast<double>(surface_.total());
  const double mean = stats.abs_sum / count;
  const double deviation = std::sqrt(std::max(stats.square_sum / count - mean * mean, 0.0));
  // A rival must be a peak that could register the pair by itself.
  const auto peak_floor = [&](double psr) { return static_cast<float>(mean + psr * deviation); };
  result.translation_unrivalled = false;
  if (prior == nullptr || !(prior->translation_radius > 0.0)) {
    findRival(peak, peak_floor(kTranslationPsrFloor), result);
    return global;
  }

  const double radius = std::min(prior->translation_radius, 0.25 * n);
  const cv::Point2d predicted = prior->translation;
  const cv::Point2d highest(peak.sub_col - n / 2, peak.sub_row - n / 2);
  const int half = static_cast<int>(std::ceil(radius));
  // The window is a three-sigma bound on the prediction: within it, a peak's height is weighted
  // by a Gaussian of a third of its radius, so that a repetitive pattern's alias near the edge
  // wins over a weaker peak at the predicted place only by being much higher.
  // The noise of a correlation surface reaches higher the more cells it has: the floors were
  // set for the largest of the N^2 cells; for the largest of a window's cells they shrink with
  // the logarithm of the count (the tail of the surface's values is about exponential).
  const double cells = (2.0 * half + 1.0) * (2.0 * half + 1.0);
  const double shrink = std::log(cells) / std::log(static_cast<double>(n) * n);
  // Values below half that floor could not make a peak of any confidence: not searched.
  const float noise_level = peak_floor(0.5 * kTranslationPsrFloor * shrink);
  const SurfacePeak near = findPeakInWindow(surface_,
                                            cv::Point(static_cast<int>(std::lround(n / 2 + predicted.x)),
                                                      static_cast<int>(std::lround(n / 2 + predicted.y))),
                                            half, half, true, shape,
                                            cv::Point2d(radius / 3.0, radius / 3.0), cv::Point(-10, -10),
                                            noise_level);
  const double near_confidence = confidenceFrom(peakToSidelobeRatio(surface_, near, stats),
                                                kTranslationPsrFloor * shrink, kTranslationPsrGood * shrink);
  if (prior->translation_ambiguous) {
    // The prediction may follow an alias: the surface's highest peak is the better reading where
    // no peak outdoes it and the prediction's own peak reaches at most a competitor's share of it;
    // where it is the prediction's own peak and has no rival, it confirms the prediction.
    findRival(peak, peak_floor(kTranslationPsrFloor), result);
    const double near_ratio = overlapNormalisedHeight(near) / overlapNormalisedHeight(peak);
    const bool same = std::abs(near.row - peak.row) <= 1 && std::abs(near.col - peak.col) <= 1;
    result.prediction_share =
        same ? (result.rival_ratio > 0.0 ? 1.0 / result.rival_ratio : kMaxDoubtShare) : near_ratio;
    // The share must hold over the pairs since the start too. A start on the motion whose lattice
    // alias rivals it stays doubted while the alias stands beside the motion's peak; where that
    // alias outgrows the motion's peak in one pair after the motion's stood highest in the pairs
    // before, one pair's heights do not make the motion so far an alias.
    const double record = doubtLogShare(result.prediction_share) + prior->doubt_log_share;
    const bool leaves = near_ratio <= kCompetingTranslationPeak && record <= std::log(kCompetingTranslationPeak);
    if (result.rival_ratio < 1.0 && (leaves || (same && result.uniqueness() >= 1.0))) {
      result.translation_unrivalled = true;
      return global;
    }
    result.rival_ratio = 0.0;  // the prediction decides, as usual
  }
  result.followed_translation = cv::Point2d(near.sub_col - n / 2, near.sub_row - n / 2);
  result.followed_confidence = near_confidence;
  // Against the highest peak, a lower one counts as much less.
  const double windowed =
      near_confidence * std::clamp(double(near.value) / std::max(double(peak.value), 1e-12), 0.0, 1.0);
  // The highest peak is plausible in the window, or on the predicted direction at up to twice or
  // half the predicted length (another depth layer of the same motion).
  const double length = std::hypot(predicted.x, predicted.y);
  bool plausible = std::hypot(highest.x - predicted.x, highest.y - predicted.y) <= radius;
  if (!plausible && length > radius) {
    const cv::Point2d along = predicted * (1.0 / length);
    const double projection = highest.x * along.x + highest.y * along.y;
    const double across = std::fabs(highest.y * along.x - highest.x * along.y);
    plausible = across <= radius && projection >= length / kMaxDepthLayerRatio &&
                projection <= kMaxDepthLayerRatio * length;
  }
  if (plausible && global >= windowed) return global;
  if (windowed > 0.0) {
    peak = near;
    result.translation_from_window = true;
    return windowed;
  }
  if (plausible) return global;
  result.translation_implausible = true;
  return 0.0;
}

double Registrar::overlapNormalisedHeight(const SurfacePeak& peak) const {
  const int n = context_->size();
  return peak.value / context_->window().overlapShare(cv::Point2d(peak.sub_col - n / 2, peak.sub_row - n / 2));
}

void Registrar::findRival(const SurfacePeak& taken, float floor, PairRegistration& result) const {
  result.rival_ratio = 0.0;
  const int n = context_->size();
  const auto cyclic = [n](int a, int b) { const int d = std::abs(a - b) % n; return std::min(d, n - d); };
  if (!(taken.value > 0.0f)) return;
  const cv::Point2d taken_shift(taken.sub_col - n / 2, taken.sub_row - n / 2);
  const double taken_height = overlapNormalisedHeight(taken);
  const double length = std::hypot(taken_shift.x, taken_shift.y);
  const cv::Point2d along = length > 0.0 ? taken_shift * (1.0 / length) : cv::Point2d();
  // A peak's own neighbourhood, as the peak-to-sidelobe ratio leaves it out [cells].
  constexpr int kNeighbourhood = 5;
  for (int r = 0; r < n; ++r) {
    const float* row = surface_[r];
    for (int c = 0; c < n; ++c) {
      const float v = row[c];
      if (!(v >= floor)) continue;
      if (cyclic(r, taken.row) <= kNeighbourhood && cyclic(c, taken.col) <= kNeighbourhood) continue;
      if (!isLocalMaximum(surface_, r, c, true)) continue;
      const cv::Point2d shift(c - n / 2, r - n / 2);
      // What does not move with the scene (vignetting, a sensor's fixed pattern) peaks at zero.
      if (std::fabs(shift.x) <= kNeighbourhood && std::fabs(shift.y) <= kNeighbourhood) continue;
      if (length > 0.0) {
        const double projection = shift.x * along.x + shift.y * along.y;
        const double across = std::fabs(shift.y * along.x - shift.x * along.y);
        if (across <= kNeighbourhood && projection >= length / kMaxDepthLayerRatio &&
            projection <= kMaxDepthLayerRatio * length) {
          continue;
        }
      }
      const double ratio = v / context_->window().overlapShare(shift) / taken_height;
      if (ratio > result.rival_ratio) {
        result.rival_ratio = ratio;
        result.rival_translation = shift;
      }
    }
  }
}

double doubtLogShare(double prediction_share) {
  return std::log(std::clamp(prediction_share, 1.0 / kMaxDoubtShare, kMaxDoubtShare));
}

double PairRegistration::uniqueness() const {
  return std::clamp((1.0 - rival_ratio) / (1.0 - kCompetingTranslationPeak), 0.0, 1.0);
}

}  // namespace oefmt
