// SPDX-License-Identifier: GPL-3.0-or-later
// Spectral registration of an image pair: rotation, zoom, translation and their energy vectors.
#pragma once

#include <algorithm>
#include <memory>
#include <optional>
#include <cstdint>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/enum_names.h"
#include "oefmt/registration/block_motion.h"
#include "oefmt/registration/registration_config.h"
#include "oefmt/registration/phase_correlation.h"
#include "oefmt/registration/spectra.h"

namespace oefmt {

enum class RegistrationMethod {
  kEnergyVectors,  ///< o-eFMT: Gaussian-fused zoom and translation energy vectors
  kClassic,        ///< Reddy-Chatterji FMT: single peaks only, no energy vectors
};

enum class RegistrationStatus {
  kOk,             ///< sharp peaks, usable
  kLowConfidence,  ///< computed, but the peaks are weak (little overlap, blur, noise)
  kTextureless,    ///< a frame is constant, black or saturated: nothing was estimated
};
inline constexpr EnumName<RegistrationStatus> kRegistrationStatusNames[] = {
    {RegistrationStatus::kOk, "ok"}, {RegistrationStatus::kLowConfidence, "low_confidence"},
    {RegistrationStatus::kTextureless, "textureless"}};
inline const char* toString(RegistrationStatus status) { return enumName(kRegistrationStatusNames, status); }

/// The registration of an older frame A to a newer frame B.
/// Axes: x right, y down (image). Angles: atan2(dy, dx) in these axes. Rotation and zoom are
/// about imageCentre(N) (warp.h), the principal point of the working frame.
struct PairRegistration {
  RegistrationStatus status = RegistrationStatus::kTextureless;
  double rotation = 0.0;     ///< theta [rad]: B is A rotated counter-clockwise on screen, (-pi, pi]
  double zoom = 1.0;         ///< s: B looks s times larger than A
  cv::Point2d translation;   ///< d [px]: shift of B's content after A is rotated+zoomed onto B
  double direction = 0.0;    ///< phi = atan2(d.y, d.x) [rad]
  double shift = 0.0;        ///< rho = |d| [px], the dominant depth's shift
  double rotation_sigma = 0.0;   ///< [rad]
  double log_zoom_sigma = 0.0;   ///< sigma of ln(s)
  double direction_sigma = 0.0;  ///< [rad]
  double shift_sigma = 0.0;      ///< [px]
  std::vector<float> zoom_energy;         ///< S: bin j <-> ln(s) = -(j - N/2) ln(b); empty in classic
  std::vector<float> translation_energy;  ///< T: bin j <-> shift j * polarRadiusStep(); empty in classic
  double rotation_zoom_peak = 0.0;  ///< height of the rotation/zoom correlation peak (0..1)
  double translation_peak = 0.0;    ///< height of the translation correlation peak (0..1)
  /// 0 (unusable) .. 1, from both peak-to-sidelobe ratios: how clearly the peaks stand out of
  /// their surfaces. The status is decided on it.
  double peak_confidence = 0.0;
  /// How far the reading can be trusted, 0 .. 1: peak_confidence times uniqueness(). A periodic
  /// texture registered without a predicted translation stands out clearly at every period, and
  /// which of those peaks is the motion is a guess: low.
  double confidence = 0.0;
  /// Which rotation/zoom peak registered: 0 the first tried (the prior's window, if any, else the
  /// highest), 1.. the next highest; kPredicted: none, the prior's rotation and zoom were used.
  int rotation_zoom_candidate = 0;
  static constexpr int kPredicted = -1;
  bool half_turn = false;           ///< the 180-degree alternative won
  /// The translation peak came from the prior's window, not the surface's highest peak (which
  /// was off the predicted motion or too weak).
  bool translation_from_window = false;
  /// The surface's highest peak was off the predicted motion and nothing in the window stood
  /// out: the registration is not confident.
  bool translation_implausible = false;
  /// With a predicted translation: the peak the prediction points at (the highest within its
  /// window, weighted towards the prediction) [px of B], and its confidence as a peak of that
  /// window (0 when none stood out). The followed depth layer's, when another layer's peak is
  /// the highest.
  cv::Point2d followed_translation;
  double followed_confidence = 0.0;
  /// Without a predicted translation (which otherwise decides between peaks), the strongest
  /// rival of the translation peak taken: another peak in its own right, not a depth layer of
  /// the same motion (the taken direction at half to twice its length), with both heights
  /// divided by the share of the frames that overlaps at their shifts (a match's peak shrinks
  /// with its overlap). Its height relative to the taken peak's (0: none), and its shift [px of
  /// B]. Near 1, the two are equally good readings: a periodic texture's alias and the motion.
  double rival_ratio = 0.0;
  cv::Point2d rival_translation;
  /// With a prior whose translation was ambiguous: the surface's highest peak was the better
  /// reading, or the prediction's and unrivalled (RegistrationPrior::translation_ambiguous), and
  /// was taken. rival_ratio is then its rival's. The estimator's doubt about its start ends.
  bool translation_unrivalled = false;
  /// With a prior whose translation was ambiguous: the prediction's own peak against the
  /// strongest other reading, both by overlap-normalised height. Below 1 where the surface's
  /// highest peak is another (the prediction's share of it), above 1 where the prediction's peak
  /// is the highest (its height over its rival's); 0: not measured. The estimator keeps the
  /// record of these over the pairs since the doubted start (RegistrationPrior::doubt_log_share).
  double prediction_share = 0.0;
  /// How much the taken peak stands above its rival: 1 when the rival reaches at most
  /// kCompetingTranslationPeak of its height, 0 when it is as high.
  double uniqueness() const;
  /// The rotation or zoom lay outside the prior's window: not confident, whatever the peaks.
  bool rotation_zoom_implausible = false;
  /// The rotation/zoom peak's own confidence, 0 to 1 (its peak-to-sidelobe ratio; 0 where it lay
  /// outside the prior's window or beyond the vehicle's turn). peak_confidence is the smaller of
  /// this and the translation's.
  double rotation_zoom_confidence = 0.0;
  /// The translation did not register (status kLowConfidence) but the rotation/zoom peak did, and
  /// rotation, zoom and refined_rotation were refined on the intensities starting from the prior's
  /// translation: only where the prior asked for it (RegistrationPrior::rotation_zoom_alone). The
  /// magnitude spectra do not depend on the translation, so the two readings stand apart; but
  /// where the translation fails nothing confirms the rotation and zoom either, and the caller
  /// judges them against the motion so far.
  bool rotation_zoom_only = false;
  /// The zoom was refined on the intensities (registration.refine_zoom), with the plane tilt
  /// set (Registrar::setPlaneTilt) along with the area-preserving stretch [a b; b -a] of B's
  /// content (oefmt/registration/plane_tilt.h; zero otherwise).
  bool zoom_refined = false;
  /// The refinement's own reading of the rotation [rad] and its sigma from the refinement's
  /// normal equations (SimilarityRefinement::rotation_sigma; 0: none, also where the refinement
  /// read the zoom without lowering its loss). `rotation` stays the surface's: the estimator
  /// weighs the two (doc/method.md).
  double refined_rotation = 0.0;
  double refined_rotation_sigma = 0.0;
  /// Where the zoom was refined: the sigma of its ln(zoom) from the refinement's normal equations
  /// (SimilarityRefinement::log_zoom_sigma; 0: none). The estimator takes it, calibrated, for the
  /// zoom's: the surface's peak width (log_zoom_sigma) says how sharp its peak is, about the same
  /// for every pair of a scene, not how far the refined zoom is from the truth.
  double refined_log_zoom_sigma = 0.0;
  /// The refinement had not settled (its last step still moved the image's edge by more than a
  /// fiftieth of a pixel): it was heading for several layers' compromise, or along a valley of a
  /// striped texture. The blocks that follow the pair's shift (BlockMotionReader) read the
  /// rotation instead: refined_rotation and its sigma are theirs, and this counts the blocks (0:
  /// the refinement's own reading, or none).
  int motion_blocks = 0;
  double stretch_a = 0.0;
  double stretch_b = 0.0;
  /// ln(zoom) added for the ground plane's tilt or the followed surface's slope
  /// (Registrar::setPlaneTilt), included in `zoom`.
  double tilt_log_zoom = 0.0;
  /// A level camera's refined pair: the part of the slope's ln(zoom) that the fitted stretch
  /// reads (logZoomOfSlope) and `zoom` does not hold, as a sigma [ln s]. The stretch is a sloping
  /// surface's, and the zoom is then off by it, or a mixture of depth layers', and then it is not:
  /// the pair cannot tell which. 0 where the whole correction was taken, for a levelled view, or
  /// where the zoom was not refined.
  double slope_log_zoom_sigma = 0.0;
  /// The older frame was warped before the translation correlation (false: the rotation/zoom
  /// moved no pixel by more than identity_warp_px and its cached spectrum served).
  bool warped = true;

  bool usable() const { return status == RegistrationStatus::kOk; }
};

/// A translation peak's rival up to this share of its height leaves the reading unambiguous.
constexpr double kCompetingTranslationPeak = 0.5;
/// One pair's PairRegistration::prediction_share counts in RegistrationPrior::doubt_log_share
/// within a factor of this either way: a pair where the prediction's peak is all but missing
/// (a frame the texture leaves flat) says no more than that it fell well behind.
constexpr double kMaxDoubtShare = 10.0;
/// ln of a PairRegistration::prediction_share as it counts in RegistrationPrior::doubt_log_share.
double doubtLogShare(double prediction_share);

/// Another depth layer of one motion moves along the same direction at most this many times as
/// far as the followed layer, or this fraction of it (tops up to half the distance to the
/// ground). A peak on the direction beyond that is not a layer of the motion: a periodic
/// texture's alias.
constexpr double kMaxDepthLayerRatio = 2.0;

/// What the motion so far predicts for a pair's rotation and zoom. The rotation/zoom surface's
/// highest values within the window are tried, and last the predicted rotation and zoom
/// themselves: low overlap, weak texture and repetitive patterns weaken the true rotation/zoom
/// peak long before the translation peak, and another peak can be the highest. A result
/// outside the window (a half turn) is ruled out. A registration on the predicted values
/// (rotation_zoom_candidate kPredicted) measured only the translation; its rotation and zoom
/// carry the prediction's sigmas.
struct RegistrationPrior {
  double rotation = 0.0;         ///< predicted theta [rad]
  double log_zoom = 0.0;         ///< predicted ln s
  double rotation_sigma = 0.0;   ///< 1-sigma of the prediction [rad]
  double log_zoom_sigma = 0.0;   ///< 1-sigma of the prediction [ln s]
  double rotation_window = 0.0;  ///< half width of the window [rad]
  double log_zoom_window = 0.0;  ///< half width of the window [ln s]
  /// Whether a rotation [rad] and ln zoom lie within the window (a NaN does not).
  bool contains(double rotation_rad, double log_zoom_value) const;
  /// How closely the motion so far pins the rotation and zoom [rad, ln s]: within the window a
  /// peak's height is weighted by a Gaussian of these widths around the prediction, so that a
  /// nearby peak of another surface (an inclined plane, whose perspective reads as a turn and a
  /// zoom) wins only by being much higher. 0: unweighted.
  double rotation_spread = 0.0;
  double log_zoom_spread = 0.0;
  /// Predicted translation d [px of the newer frame] of the followed depth layer and the radius
  /// of the window around it [px]; radius 0: no translation prediction. The highest translation
  /// peak stands when it lies in the window or on the predicted direction of motion (another
  /// depth layer moves along it, up to twice or half as far). Otherwise, and when it is too weak,
  /// the highest peak within the window is taken if it stands out from the surface as a peak
  /// that could be anywhere in a window of that size would have to; if none does, the
  /// registration is not confident (a repetitive texture's alias, or a pair that does not match).
  cv::Point2d translation;
  double translation_radius = 0.0;
  /// How far the last steps strayed from the prediction's constant motion [px]: its own
  /// uncertainty, without the vehicle's possible acceleration.
  double translation_sigma = 0.0;
  /// The motion so far rests on readings that a rival peak matched as well (a periodic texture
  /// since the last start): the prediction may follow an alias. The surface's highest peak is
  /// then taken wherever it lies when no peak outdoes it as PairRegistration::rival_ratio
  /// measures and the window's peak reaches at most kCompetingTranslationPeak of it, in this
  /// pair and over the pairs since the start (doubt_log_share), or when it is the window's peak
  /// and nothing rivals it, which confirms the prediction
  /// (PairRegistration::translation_unrivalled).
  bool translation_ambiguous = false;
  /// With translation_ambiguous: the sum of ln PairRegistration::prediction_share over the
  /// pairs since the doubted start, each within a factor of kMaxDoubtShare either way. Above 0
  /// where the prediction's peak stood above the other readings more than it fell behind them.
  double doubt_log_share = 0.0;
  /// Where the translation does not register but the window's rotation/zoom peak does, refine
  /// that rotation and zoom from the predicted translation (translation_radius > 0) and report
  /// them (PairRegistration::rotation_zoom_only) rather than the prediction's own.
  bool rotation_zoom_alone = false;
};

/// The shifts [px] of a registered pair's other depth layers, which the zoom refinement tests its
/// blocks against: the four strongest local maxima of its translation energy vector further than
/// 3 px from its shift, along its direction (`shift_per_bin`: Registrar::shiftPerBin()). However
/// weak, a peak costs only time: a shift that nothing follows fits no block better.
std::vector<cv::Point2d> otherLayerShifts(const PairRegistration& registration, double shift_per_bin);

/// Correlation surfaces of the last registration, for diagnostics and plots.
struct RegistrationSurfaces {
  cv::Mat1f rotation_zoom;      ///< rows: rotation, columns: log-zoom (centred)
  cv::Mat1f translation;        ///< centred Cartesian translation surface
  cv::Mat1f translation_polar;  ///< rows: direction, columns: radius (energy-vector method only):
                                ///< the band of rows around the peak direction that was unwrapped
  int translation_polar_first_row = 0;  ///< direction row of translation_polar's first row
};

/// Registers frame pairs. Holds per-thread scratch buffers, so use one Registrar per thread;
/// several Registrars can share one SpectralContext (FFT plans and tables).
class Registrar {
 public:
  explicit Registrar(const RegistrationConfig& config);
  explicit Registrar(std::shared_ptr<const SpectralContext> context);

  /// Spectra of a camera image of any size and supported type (see prepareImage).
  FrameSpectra analyse(const cv::Mat& image, ChannelOrder order = ChannelOrder::kBgr);
  /// Spectra of an already prepared N x N image.
  FrameSpectra analyse(const PreparedImage& image);

  /// Registers older -> newer. Throws InputError if a frame is empty or the sizes differ.
  /// max_rotation [rad]: the largest turn the pair can hold (the vehicle's largest yaw rate over
  /// the frames' interval). Below a quarter turn it decides the half-turn ambiguity of the
  /// rotation surface (the smaller turn), and a rotation beyond it is never confident: a
  /// periodic texture matches itself turned by a half or a quarter turn as well as unturned.
  PairRegistration registerPair(const FrameSpectra& older, const FrameSpectra& newer,
                                RegistrationMethod method = RegistrationMethod::kEnergyVectors,
                                RegistrationSurfaces* surfaces = nullptr,
                                const RegistrationPrior* prior = nullptr, double max_rotation = CV_PI);

  const SpectralContext& context() const { return *context_; }
  std::shared_ptr<const SpectralContext> sharedContext() const { return context_; }
  /// ln(b): change of ln(zoom) per zoom-energy bin.
  double logZoomPerBin() const;
  /// Pixels of shift per translation-energy bin.
  double shiftPerBin() const { return context_->polarRadiusStep(); }
  /// The translation energy vector of the pair older -> newer along `direction` [rad], its
  /// energy row searched near there (as PairRegistration::translation_energy, which is read along
  /// the chosen peak's direction), from its correlation surface `length` px out; empty unless
  /// that pair is the one registered last (FrameSpectra::serial).
  std::vector<float> translationEnergyAlong(const FrameSpectra& older, const FrameSpectra& newer,
                                            double direction, double length);
  /// Rotation/zoom peaks this Registrar tries (default: the configuration's
  /// rotation_zoom_candidates); clamped to >= 1.
  void setRotationZoomCandidates(int candidates) { rotation_zoom_candidates_ = std::max(1, candidates); }
  /// Whether the image blocks read the rotation of a pair whose zoom refinement did not settle
  /// (PairRegistration::motion_blocks; default: yes, for frames of at least 64 px).
  void setBlockReading(bool on) { block_reading_ = on; }
  /// Frames levelled by an attitude source: the ground plane's tilt left in the level view
  /// [1/px, image axes] (the source's error), for which the refined zooms are corrected
  /// (oefmt/registration/plane_tilt.h) from the tilt set, the reading of the pairs' stretch
  /// (PairRegistration::stretch_a, stretch_b) over many pairs. nullopt (the default): a level
  /// camera; each pair's own stretch is read as the slope of the surface under it, which corrects
  /// its zoom as far as it brings it back towards the prior's (none without a prior).
  void setPlaneTilt(const std::optional<cv::Point2d>& tilt) { plane_tilt_ = tilt; }

 private:
  // The rotation/zoom correlation surface of the pair, into rotation_zoom_surface_.
  void correlateRotationZoom(const FrameSpectra& older, const FrameSpectra& newer);
  // Rotation, zoom, translation and confidence with the given peak of the rotation/zoom
  // surface. The prior's translation, if any, guides the translation peak.
  void registerOnce(const FrameSpectra& older, const FrameSpectra& newer, RegistrationMethod method,
                    PairRegistration& result, const SurfacePeak& rotation_zoom_peak,
                    RegistrationSurfaces* surfaces, const RegistrationPrior* prior);
  // The registration with the peaks of the prior's window (see RegistrationPrior).
  PairRegistration registerInWindow(const FrameSpectra& older, const FrameSpectra& newer,
                                    RegistrationMethod method, const RegistrationPrior& prior,
                                    RegistrationSurfaces* surfaces);
  // Each returns the peak-to-sidelobe ratio of its correlation surface.
  double registerRotationZoom(RegistrationMethod method, PairRegistration& result,
                              const SurfacePeak& peak);
  // The rotation/zoom surface's position of the prior's prediction (x = column, y = row).
  cv::Point2d windowCentre(const RegistrationPrior& window) const;
  // The highest peak of the rotation/zoom surface within the prior's window, weighted towards
  // the prediction (findPeakInWindow), other than the peak at `exclude`.
  SurfacePeak windowPeak(const RegistrationPrior& window, cv::Point exclude = {-10, -10}) const;
  // That Gaussian weight of a surface position.
  double windowWeight(const RegistrationPrior& window, cv::Point peak) const;
  // RegistrationPrior::rotation_zoom_alone: a result whose translation did not register takes
  // its rotation and zoom refined from the predicted translation, where its rotation/zoom peak
  // was confident (PairRegistration::rotation_zoom_only).
  void refineRotationZoomAlone(const FrameSpectra& older, const FrameSpectra& newer,
                               const RegistrationPrior& prior, PairRegistration& result);
  // The translation alone, with the prior's rotation and zoom.
  void registerOnPrior(const FrameSpectra& older, const FrameSpectra& newer, RegistrationMethod method,
                       const RegistrationPrior& prior, PairRegistration& result,
                       RegistrationSurfaces* surfaces);
  // warped_spectrum_: the older frame warped by the result's rotation and zoom and transformed
  // (result.warped false: it would move no pixel noticeably, and was not warped).
  void warpOlder(const FrameSpectra& older, PairRegistration& result);
  // The translation's confidence (0..1) instead of a peak-to-sidelobe ratio.
  double registerTranslation(const FrameSpectra& older, const FrameSpectra& newer,
                             RegistrationMethod method, PairRegistration& result,
                             bool test_half_turn, const RegistrationPrior* prior);
  // The translation peak of surface_: the highest, or the prior's window's; sets the result's
  // window flags and returns the peak's confidence.
  double chooseTranslationPeak(const RegistrationPrior* prior, SurfacePeak& peak,
                               PairRegistration& result);
  // Sets the result's rival of the taken translation peak (PairRegistration::rival_ratio): the
  // highest local maximum of surface_ that reaches `floor` and lies outside the taken peak's
  // neighbourhood and depth layers.
  void findRival(const SurfacePeak& taken, float floor, PairRegistration& result) const;
  // A translation peak's height divided by the window's overlap share at its shift: a perfect
  // match's height at any shift.
  double overlapNormalisedHeight(const SurfacePeak& peak) const;

  std::shared_ptr<const SpectralContext> context_;
  SpectraBuilder builder_;
  std::optional<BlockMotionReader> blocks_;  // frames of at least BlockMotionReader::kMinImageSize
  bool block_reading_ = true;
  // Scratch, reused across calls.
  cv::Mat2f cross_power_, small_spectrum_, rotation_zoom_power_;
  cv::Mat1f surface_;  // the translation correlation surface: a view of cross_power_ (in-place FFT)
  cv::Mat1f rotation_zoom_surface_;  // a view of rotation_zoom_power_
  SurfaceStats rotation_zoom_stats_;  // of the whole surface, for the peak-to-sidelobe ratios
  SurfacePeak rotation_zoom_highest_;
  cv::Mat1f small_surface_, polar_;
  cv::Mat2f warped_spectrum_;
  int polar_first_row_ = 0;
  // The frames (FrameSpectra::serial) whose translation surface surface_ holds; 0 for none.
  std::pair<std::uint64_t, std::uint64_t> surface_pair_{0, 0};
  int rotation_zoom_candidates_;
  std::optional<cv::Point2d> plane_tilt_;
  double max_rotation_ = CV_PI;  // of the pair being registered (see registerPair)
};

}  // namespace oefmt
