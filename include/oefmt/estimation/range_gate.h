// SPDX-License-Identifier: GPL-3.0-or-later
// Downward rangefinder readings turned into altitudes above the estimator's reference plane.
//
// A rangefinder reads the distance to whatever is below: the ground, or a roof when the vehicle
// passes over one. The estimator's altitude is above one plane, the one whose shift its steps
// follow. The translation energy vector of the newest pair holds a peak for every depth layer in
// view, at a shift inversely proportional to the layer's depth; so a reading of layer l's surface
// R, over the depth ratio c_l = (followed shift) / (layer l's shift), is the reference plane's
// depth. A reading is taken when R / (predicted altitude) is within a gate of one of those
// ratios (1 for the reference plane itself). When the readings keep disagreeing, but
// consistently with each other, the estimate has drifted beyond the gate: the gate then opens to
// them again, as readings of the reference plane.
#pragma once

#include <cstddef>
#include <deque>
#include <optional>
#include <vector>

#include "oefmt/estimation/attitude.h"
#include "oefmt/estimation/estimator.h"

namespace oefmt {

class RangeGate {
 public:
  /// gate: largest relative difference of a reading from the prediction that is taken;
  /// relock_after: this many consecutive readings refused, all within `gate` of their median,
  /// are taken again.
  explicit RangeGate(double gate = 0.08, int relock_after = 15);

  /// `vertical`: the reading turned vertical (range times the cosine of the tilt) [m];
  /// `predicted`: the estimator's altitude [m]; `depth_ratios`: the layers' c_l (depthRatios()).
  /// The altitude above the reference plane the reading measures, or nothing.
  /// `centre_ratio` (> 0): the layer below the camera is known (centreDepthRatio()); only its
  /// ratio is tried.
  std::optional<double> measure(double vertical, double predicted, const std::vector<double>& depth_ratios = {},
                                double centre_ratio = 0.0);

  long accepted() const { return accepted_; }
  long refused() const { return refused_; }

 private:
  double gate_;
  int relock_after_;
  std::deque<double> recent_ratios_;  // of consecutive refused readings
  long accepted_ = 0;
  long refused_ = 0;
};

/// Keeps an estimator's altitude, and with it the scale, metric with a downward rangefinder: each
/// tracked frame's reading (turned vertical), taken by a RangeGate through the frame's depth
/// layers, corrects the altitude (Estimator::observeAltitude).
class RangeAltitude {
 public:
  /// reading_sigma: the rangefinder's noise [m]; attitude_sigma: how well the camera's tilt is
  /// known [rad] (a step of length L may climb or descend L times it unseen by the images' zoom).
  explicit RangeAltitude(double reading_sigma = 0.05, double attitude_sigma = 0.5 * M_PI / 180.0);

  /// After `estimator` gave `estimate` for a frame: its reading (nothing without one), read at
  /// `beam` (see centreDepthRatio()). True when the reading corrected the altitude; the
  /// estimator's pose() is then the corrected one.
  bool update(Estimator& estimator, const Estimate& estimate, std::optional<double> vertical,
              cv::Point2d beam = {0.0, 0.0});

  const RangeGate& gate() const { return gate_; }

 private:
  RangeGate gate_;
  double reading_sigma_;
  double attitude_sigma_;
  double last_x_ = 0.0, last_y_ = 0.0;  // where the altitude was last measured
};

/// The depth ratio c = (the followed layer's shift) / (the shift at the image centre) of a pair:
/// which layer a downward rangefinder, which reads the surface below the camera, sees. `older`
/// and `newer` are the pair's N x N grey frames and `motion` the pair's motion as the estimator
/// integrated it (the followed layer's). The newer frame's centre patch (N / 4 wide), moved by
/// the followed translation, is phase-correlated with the older frame's turned and zoomed into
/// it: what is left is the centre's own shift beyond the followed layer's. Nothing when the
/// frames do not fit, the motion is below a pixel, a patch leaves its frame, or the correlation
/// peak does not stand out of the noise (three times the largest value a patch of unrelated
/// content reaches): a low-texture centre, or a centre whose shift differs from the followed
/// layer's by more than half a patch.
/// `beam`: where the reading lies in the newer frame, relative to its centre [px]
/// (opticalAxisInNadirView() for a levelled tilted frame; zero for a level camera).
std::optional<double> centreDepthRatio(const cv::Mat1f& older, const cv::Mat1f& newer, const PairMotion& motion,
                                       cv::Point2d beam = {0.0, 0.0});

/// Where the rangefinder's reading lies in a frame, relative to its centre [px] (the `beam` of
/// centreDepthRatio()): the optical axis of a camera tilted by `tilt` in its levelled view of
/// focal length `fx` (opticalAxisInNadirView()); the centre for a frame taken as level (no tilt).
cv::Point2d beamInFrame(const std::optional<CameraTilt>& tilt, double fx);

/// How many frames' readings vote which layer the rangefinder saw before the scale is taken from
/// them (rangeScale): oefmt_offline runs them ahead, the node rescales after them.
inline constexpr std::size_t kRangeVoteFrames = 20;

/// One rangefinder reading beside the estimator's altitude and layers at its frame.
struct RangeObservation {
  double vertical = 0.0;              ///< the reading turned vertical [m]
  double predicted = 0.0;             ///< the estimator's altitude then (any consistent unit)
  std::vector<double> depth_ratios;   ///< depthRatios() of that frame
  /// centreDepthRatio() of that frame, the layer below the camera (0: not measured). Where it is
  /// known the reading is taken as that layer's, and depth_ratios are not consulted.
  double centre_ratio = 0.0;
};

/// The observation of a reading for the frame `estimator` just gave `estimate` for: the
/// estimator's altitude, the depth ratios of that frame's layers and the layer below the reading
/// at `beam` (see centreDepthRatio()).
RangeObservation rangeObservation(const Estimator& estimator, const Estimate& estimate, double vertical,
                                  cv::Point2d beam = {0.0, 0.0});

/// The factor that turns the estimator's altitudes into the reference plane's metric depth, from
/// the first frames' readings, whichever layer each read: every reading proposes one factor per
/// layer (vertical / (c_l predicted)), and the factor most readings fit (within `gate`, through
/// some layer of theirs) wins; ties (readings that always saw the same layers) go to the smaller
/// factor: the readings saw the farthest layer, the ground, which is most often below. Nothing
/// unless at least `min_support` readings fit it.
std::optional<double> rangeScale(const std::vector<RangeObservation>& observations, double gate = 0.08,
                                 int min_support = 3);

/// The depth ratios c_l = followed_shift / (shift of layer l) of the layers in a translation
/// energy vector (bin j <-> shift j * shift_per_bin): its local maxima of at least a quarter of its
/// highest, each refined by a parabola through its neighbours. Empty without an energy vector.
std::vector<double> depthRatios(const std::vector<float>& translation_energy, double shift_per_bin,
                                double followed_shift);

}  // namespace oefmt
