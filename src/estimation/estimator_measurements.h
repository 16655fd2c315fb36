// SPDX-License-Identifier: GPL-3.0-or-later
// Internal to the estimator: registrations and pattern matches turned into calibrated motions and
// optimizer observations.
#pragma once

#include <deque>
#include <optional>
#include <vector>

#include "oefmt/estimation/estimator_config.h"
#include "oefmt/estimation/local_optimizer.h"
#include "oefmt/estimation/pair_motion.h"
#include "oefmt/registration/pattern_matching.h"
#include "oefmt/registration/registration.h"
#include "oefmt/registration/robust_statistics.h"

namespace oefmt {
namespace detail {

/// Smallest sigma of a shift handed on [px], so that no weight becomes infinite.
constexpr double kMinShiftSigma = 0.01;

/// A registration as a PairMotion, its peak widths turned into error sigmas (UncertaintyConfig);
/// non-finite values become "no motion" with wide sigmas.
PairMotion calibrated(const PairRegistration& registration, const UncertaintyConfig& uncertainty);

/// 1-sigma of |d| (along d) of a motion's translation.
double alongTrackSigma(const PairMotion& motion);

/// `motion` moved to `length` along its own direction, with 1-sigmas along and across it.
PairMotion withLength(const PairMotion& motion, double length, double along, double across);

/// The motion of one frame interval from a motion spanning `gap` intervals.
PairMotion perInterval(const PairMotion& motion, int gap);

/// The step a frame that could not be registered is extrapolated with: the last step's
/// translation, turned and zoomed at the median rates of `rates` (the last steps that measured
/// their rotation and zoom; the last step's own rates when there are none). The frames fail where
/// the registration weakens, and the last step before them is often the one whose turn went
/// wrong: repeated on every predicted frame it bent the trajectory by as much each time.
PairMotion extrapolatedStep(const PairMotion& last, const std::deque<PairMotion>& rates);

/// The turn per frame interval that the last three steps of `rates` (those that measured their
/// rotation) give the next one where their turn changed steadily, growing or shrinking at each
/// step: the middle one continued by twice the smaller of the two changes (a vehicle that eases
/// into or out of a turn goes on doing so; a single wrong step makes the sequence either not
/// steady or its change the larger one). Nothing with fewer than three such steps or an
/// unsteady sequence (then their median is the prediction). [rad]
std::optional<double> steadilyChangingTurn(const std::deque<PairMotion>& rates);

/// The deviations of the last measured rates (a pair's turn, or its log-zoom) from what the
/// rates before them predicted, which tell a reading that is an outlier of the measurement from a
/// change of the rate. Where one pair's registration is pulled off the motion (another depth
/// layer takes the translation peak, a periodic texture's alias), its rotation or zoom deviates
/// from the prediction by several times what the steps before it did, while the prediction
/// itself stays within their spread. One such reading in a row is taken as an outlier; a second
/// is a change of the rate.
class RateDeviations {
 public:
  /// frames: how many of the last accepted deviations are remembered; support: how many are
  /// needed before any reading is judged; gate: the outlier's distance in their spreads; floor:
  /// the smallest spread.
  RateDeviations(std::size_t frames, std::size_t support, double gate, double floor);

  /// Judges a reading that deviates by `deviation` from its prediction: true for an outlier
  /// (not remembered). Any other reading is remembered. A reading off a pair that cannot tell a
  /// change of the rate (`may_change_rate` false) is an outlier wherever it lies beyond the gate,
  /// however many came before it, and leaves the record untouched.
  bool outlier(double deviation, bool may_change_rate = true);
  /// Whether `deviation` lies beyond the gate, judged without remembering it (false until the
  /// support is known).
  bool beyondGate(double deviation) const;
  /// Whether enough deviations are remembered to judge one, and `deviation` lies within the gate.
  bool withinGate(double deviation) const;
  /// Whether enough deviations are remembered to judge one.
  bool supported() const { return deviations_.size() >= support_; }
  /// The remembered deviations' spread as a normal sigma (at least the floor).
  double spread() const;
  void clear();

 private:
  std::size_t frames_;
  std::size_t support_;
  double gate_;
  double floor_;
  std::deque<double> deviations_;  // absolute values
  bool last_outlier_ = false;
};

/// PMT options; the no-motion bins are skipped when the reference peak lies well beyond them.
StretchMatchOptions stretchOptions(const MatchingConfig& matching, double init, double key,
                                   double reference_bin);
ShiftMatchOptions shiftOptions(const MatchingConfig& matching);

/// The ambiguity of a step's length: the largest distance of an `alternatives` length (another
/// reading of the same step: the PMT stretch, the highest correlation peak) from `length`, among
/// those off it by more than `layer_gate` x length (closer ones are the same reading within the
/// layers' noise) and within `window` of it (the acceleration window: further ones the vehicle
/// cannot have flown; `window` <= 0: no window). 0 when every alternative agrees or is ruled out;
/// non-positive or non-finite alternatives are ignored.
double lengthSpread(double length, const std::vector<double>& alternatives, double layer_gate, double window);

/// Whether a step's length came from its pair's own translation peak (the correlation peak, the
/// window's peak, a change of speed, or the loop over it) rather than from a weaker reading (a
/// layer's energy peak, a layer ratio, the stretch, the vouched ratios, the prediction): only such
/// a pair registered the followed layer itself, and only its turn can tell a change of the turn
/// rate from a reading of another layer or an alias.
bool lengthFromOwnPeak(LengthSource source);

/// Whether a step of `length` [px], read off `source`, gives way to the `vouched` length (the
/// ratios the layers in view held over the last steps, LayerRatioMemory). `steady` is the length
/// the motion so far predicts; `tolerance` the ratios' own (relative). The layers mend a step that
/// broke away from the motion so far (further than `layer_gate` from the vouched length) and never
/// move one that held to it. Within the gate a weak reading (the followed layer taken as an energy
/// peak near the steady length, or a layer ratio between the pairs) gives way too where the
/// vouched length and the prediction, two independent readings, agree (within twice the
/// tolerance) and the step lies clearly further from the prediction: on a periodic texture an
/// alias of the followed layer stands within the gate, its peak low, wherever that layer has left
/// the view.
bool vouchedLengthWins(double length, LengthSource source, double vouched, double steady, double layer_gate,
                       double tolerance);

/// `motion` with `spread`^2 added to its translation covariance along its direction.
PairMotion withAlongTrackSpread(const PairMotion& motion, double spread);

/// What a pair's observations are related to: pair 0-1 of the window.
struct Reference {
  cv::Point2d translation;          ///< d01 [px of frame 1]
  double shift = 0.0;               ///< |d01|
  double shift_sigma = 0.0;         ///< its 1-sigma
  double raw_log_zoom = 0.0;        ///< ln s of the registration that produced S01
  double raw_log_zoom_sigma = 0.0;
  const std::vector<float>* translation_energy = nullptr;  ///< T01 (may be empty)
};

/// The optimizer observations of one pair (1-2 or 0-2) spanning `intervals` times pair 0-1's
/// frame intervals, and its starting value `initial`:
/// - the registration (rotation, zoom, d) and, if valid, the PMS zoom relative to S01;
/// - the PMT length prediction lambda |d01|; a correlation peak whose length is off the
///   prediction by more than tracking.layer_gate belongs to another depth layer (or is an alias):
///   only its direction is kept and the translation energy peak nearest to the prediction (the
///   followed layer) gives the length;
/// - a weak prior that the pair continues pair 0-1's motion (tracking.motion_prior_sigma).
///
/// With a predicted translation (`prior`, from the motion so far), the prediction decides which
/// peak is the followed layer's instead of the PMT: the correlation peak when it lies within the
/// prediction's gate (tracking.layer_gate of it, or three sigmas of the motion's spread if wider)
/// and, where the PMT reads the followed layer's length inside that gate, within
/// tracking.layer_gate of the PMT's length; else the peak the prediction points at
/// (PairRegistration::followed_translation) when it stands out; else the followed layer is not
/// in view: the layers of steadyLayerStep (the followed layer's trace in the energy vector, or a
/// layer seen in both pairs) give its length and the correlation peak its direction if that
/// lies on the predicted one (another layer of the same motion; otherwise nothing of it: a
/// repetitive texture's alias); where no layer tells, a correlation peak on the direction within
/// the acceleration window stands (the motion changed), unless the followed layer leaves a trace
/// at the predicted length: an energy peak within tracking.layer_gate of it that reaches
/// tracking.layer_min_fraction of the maximum (the layer is in view, the speed did not change,
/// and its trace gives the length); else the prediction's length. Not over
/// `skipped_frames` (the pair spans frames that were not registered): there the prediction
/// reaches further, its acceleration window grew with the square of the time, and a peak inside
/// it says less of a change of speed than a pair over one interval does. The prediction's length
/// stands and a real change shows at the next pair.
PairObservations observe(const PairRegistration& registration, const PairMotion& measured,
                         const MatchResult& pmt, const MatchResult& pms, const Reference& reference,
                         const EstimatorConfig& config, double shift_per_bin,
                         double log_zoom_per_bin, double intervals, const RegistrationPrior* prior,
                         PairMotion& initial, bool skipped_frames = false);

/// The step of pair 1-2 that keeps following one depth layer. `candidate` is the loop's step
/// (without a loop, the gated measurement). When its length is off steady speed (pair 0-1's
/// shift continued over `intervals`) by more than tracking.layer_gate:
/// - a peak of pair 1-2's translation energy vector within layer_gate of the steady length (the
///   followed layer) gives the length;
/// - without one (the layer has left the view), the layers seen in both pairs at steady speed
///   (a peak of pair 1-2 and one of pair 0-1's `translation01` within layer_gate of each other
///   over the intervals) give the speed ratio, the one nearest to steady wins, and the step is
///   the steady length times it: the followed layer's scale is kept.
/// Pair 1-2's peaks must reach tracking.steady_layer_min_fraction of its maximum, pair 0-1's
/// tracking.layer_min_fraction. A hop to another layer's peak (the dominant peak's, or a stretch
/// matched to the wrong layer, in one pair or in both pairs of the loop alike) is far likelier
/// than a speed change by a layer ratio within one frame interval; a real speed change leaves no
/// layer at steady speed and stands (one by exactly the ratio of two layers' depths cannot be
/// told from a hop). Slow motion (a steady length within 4 x matching.skip_bins, where a static
/// pattern's no-motion peak lies) is left alone too.
/// `steady` is the followed layer's expected length [px] (pair 0-1's continued).
/// `source` (if given) is set to LengthSource::kEnergyPeak or kLayerRatio where the step moved.
PairMotion steadyLayerStep(const PairMotion& candidate, const PairRegistration& registration12,
                           const std::vector<float>& translation01, double steady,
                           const EstimatorConfig& config, double shift_per_bin, double intervals,
                           LengthSource* source = nullptr);

}  // namespace detail
}  // namespace oefmt
