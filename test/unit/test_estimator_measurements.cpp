// SPDX-License-Identifier: GPL-3.0-or-later
// The estimator's internal decisions on one pair's observations (src/estimation/estimator_measurements).
#include <gtest/gtest.h>

#include <cmath>
#include <deque>
#include <vector>

#include "estimation/estimator_measurements.h"

namespace oefmt {
namespace {

constexpr double kShiftPerBin = 1.0;

PairMotion motionAlongX(double shift) {
  PairMotion m;
  m.translation = {shift, 0.0};
  m.translation_covariance = cv::Matx22d::eye();
  return m;
}

// A translation energy vector whose layers' peaks lie at the given bins with the given heights.
std::vector<float> energyWithPeaks(const std::vector<std::pair<double, double>>& peaks) {
  std::vector<float> v(256, 0.0f);
  for (int j = 0; j < 256; ++j) {
    for (const auto& [bin, height] : peaks) {
      v[j] += static_cast<float>(height * std::exp(-0.5 * (j - bin) * (j - bin) / 4.0));
    }
  }
  return v;
}

// Pair 1-2 of such a scene.
PairRegistration withPeaks(const std::vector<std::pair<double, double>>& peaks) {
  PairRegistration r;
  r.translation_energy = energyWithPeaks(peaks);
  return r;
}

// Pair 0-1 of the two-layer scene of most cases below: ground 92.7 px, roofs x1.43.
const std::vector<float>& groundAndRoofs01() {
  static const std::vector<float> v = energyWithPeaks({{92.7, 1.0}, {132.5, 0.5}});
  return v;
}

// Pair 0-1 moved 92.7 px along the ground. The roofs (x1.43) took over pair 1-2's dominant
// peak and the loop followed them; the ground's peak, 1/12 of theirs, is still at the steady
// length: the step goes back to it, direction and all else kept.
TEST(SteadyLayerStep, AHopToTheRoofsGoesBackToTheGround) {
  PairMotion loop = motionAlongX(132.5);
  loop.translation = {132.5 * std::cos(0.3), 132.5 * std::sin(0.3)};
  LengthSource source = LengthSource::kNone;
  const PairMotion step = detail::steadyLayerStep(loop, withPeaks({{92.7, 0.08}, {132.5, 1.0}}), groundAndRoofs01(),
                                                  (92.7) * 1.0, EstimatorConfig(), kShiftPerBin, 1.0, &source);
  EXPECT_NEAR(step.shift(), 92.7, 0.1);
  EXPECT_EQ(source, LengthSource::kEnergyPeak);
  EXPECT_NEAR(step.direction(), 0.3, 1e-9);
  EXPECT_TRUE(step.finite());
  EXPECT_GE(cv::determinant(step.translation_covariance), 0.0);
}

// A real speed change (x1.6, one layer) leaves no peak at the steady length: it stands.
TEST(SteadyLayerStep, ASpeedChangeStands) {
  const PairMotion loop = motionAlongX(148.3);
  LengthSource source = LengthSource::kPeak;
  const PairMotion step = detail::steadyLayerStep(loop, withPeaks({{148.3, 1.0}}), groundAndRoofs01(), (92.7) * 1.0,
                                                  EstimatorConfig(), kShiftPerBin, 1.0, &source);
  EXPECT_DOUBLE_EQ(step.shift(), 148.3);
  EXPECT_EQ(source, LengthSource::kPeak);  // untouched: the step stood
}

// Pair 0-2 spans two of pair 0-1's intervals: steady speed means twice its shift.
TEST(SteadyLayerStep, SteadySpeedScalesWithTheFrameIntervals) {
  const PairMotion loop = motionAlongX(265.0);
  const PairMotion step = detail::steadyLayerStep(loop, withPeaks({{185.4, 0.2}, {265.0, 1.0}}), groundAndRoofs01(),
                                                  (92.7) * 2.0, EstimatorConfig(), kShiftPerBin, 2.0);
  EXPECT_NEAR(step.shift(), 185.4, 0.1);
}

// A step at steady speed, a peak too small to be a layer (and no layer that pair 0-1 saw at
// steady speed), or no reference: the step stands.
TEST(SteadyLayerStep, StepsAtSteadySpeedOrWithoutEvidenceStand) {
  EstimatorConfig config;
  const std::vector<float> ground01 = energyWithPeaks({{92.7, 1.0}});
  EXPECT_DOUBLE_EQ(detail::steadyLayerStep(motionAlongX(94.0), withPeaks({{92.7, 1.0}}), ground01,
                                           (92.7) * 1.0, config, kShiftPerBin, 1.0).shift(), 94.0);
  EXPECT_DOUBLE_EQ(detail::steadyLayerStep(motionAlongX(132.5), withPeaks({{92.7, 0.01}, {132.5, 1.0}}),
                                           ground01, (92.7) * 1.0, config, kShiftPerBin, 1.0).shift(),
                   132.5);
  EXPECT_DOUBLE_EQ(detail::steadyLayerStep(motionAlongX(132.5), withPeaks({{92.7, 0.5}, {132.5, 1.0}}),
                                           groundAndRoofs01(), (0.0) * 1.0, config, kShiftPerBin, 1.0)
                       .shift(),
                   132.5);
  config.tracking.steady_layer_min_fraction = 1.0;  // only the largest peak would do
  EXPECT_DOUBLE_EQ(detail::steadyLayerStep(motionAlongX(132.5), withPeaks({{92.7, 0.5}, {132.5, 1.0}}),
                                           ground01, (92.7) * 1.0, config, kShiftPerBin, 1.0).shift(),
                   132.5);
}

// The followed layer (roofs, 132.5 px in pair 0-1) has left the view; the loop took the middle
// layer's peak (119.5 px). The layers that pair 0-1 also saw keep their speed: the step keeps the
// roofs' scale, and follows a small speed change of those layers.
TEST(SteadyLayerStep, TheFollowedLayerLeavingKeepsItsScale) {
  const std::vector<float> three01 = energyWithPeaks({{92.7, 1.0}, {119.5, 0.6}, {132.5, 0.3}});
  LengthSource source = LengthSource::kNone;
  const PairMotion steady = detail::steadyLayerStep(
      motionAlongX(119.5), withPeaks({{92.7, 1.0}, {119.5, 0.7}}), three01, (132.5) * 1.0,
      EstimatorConfig(), kShiftPerBin, 1.0, &source);
  EXPECT_NEAR(steady.shift(), 132.5, 0.2);
  EXPECT_EQ(source, LengthSource::kLayerRatio);
  const PairMotion faster = detail::steadyLayerStep(
      motionAlongX(121.9), withPeaks({{94.55, 1.0}, {121.9, 0.7}}), three01, (132.5) * 1.0,
      EstimatorConfig(), kShiftPerBin, 1.0);
  EXPECT_NEAR(faster.shift(), 132.5 * 1.02, 0.3);
  // A speed change beyond layer_gate for every layer: nothing was seen at steady speed, it stands.
  // (A change by a ratio between two layers' depths, x1.29 here, cannot be told from a hop.)
  const PairMotion changed = detail::steadyLayerStep(
      motionAlongX(119.5 * 1.6), withPeaks({{92.7 * 1.6, 1.0}, {119.5 * 1.6, 0.7}}), three01,
      (132.5) * 1.0, EstimatorConfig(), kShiftPerBin, 1.0);
  EXPECT_NEAR(changed.shift(), 119.5 * 1.6, 1e-9);
}

// Pair 0-1 of a scene with walls between its levels: the ground 92.7 px, the followed tops
// 110.0 px, higher tops 132.5 px.
const std::vector<float>& threeLevels01() {
  static const std::vector<float> v = energyWithPeaks({{92.7, 1.0}, {110.0, 0.6}, {132.5, 0.5}});
  return v;
}

// Pair 1-2 at steady speed: the followed tops have left the view, and a wall's peak stands at
// 114.0 px, inside layer_gate of their 110.0. The ground and the higher tops keep their speed, so
// the wall's peak is another layer: the step keeps the followed tops' length, by the speed the
// other two agree on. Taken for the followed layer, the length moved 3.6 % with no change of
// speed, and on from wall to wall at the next pairs. Two weak wall peaks (a fiftieth of the
// highest, below tracking.steady_layer_min_fraction) that happen to lie 3.6 % apart in the two
// pairs testify to nothing.
TEST(SteadyLayerStep, APeakInsideTheGateThatTheOtherLayersRefuteIsAnotherLayer) {
  LengthSource source = LengthSource::kNone;
  const PairMotion step = detail::steadyLayerStep(motionAlongX(132.5), withPeaks({{92.7, 1.0}, {114.0, 0.3}, {132.5, 0.5}}),
                                                  threeLevels01(), 110.0, EstimatorConfig(), kShiftPerBin, 1.0, &source);
  EXPECT_NEAR(step.shift(), 110.0, 0.2);
  EXPECT_EQ(source, LengthSource::kLayerRatio);
  const EstimatorConfig config;
  ASSERT_LT(config.tracking.layer_min_fraction, 0.02);
  ASSERT_GT(config.tracking.steady_layer_min_fraction, 0.02);
  const std::vector<float> with_wall01 = energyWithPeaks({{92.7, 1.0}, {110.0, 0.6}, {132.5, 0.5}, {160.0, 0.02}});
  const PairMotion past_walls = detail::steadyLayerStep(
      motionAlongX(132.5), withPeaks({{92.7, 1.0}, {114.0, 0.3}, {132.5, 0.5}, {160.0 * 114.0 / 110.0, 0.02}}),
      with_wall01, 110.0, config, kShiftPerBin, 1.0, &source);
  EXPECT_NEAR(past_walls.shift(), 110.0, 0.2);
  EXPECT_EQ(source, LengthSource::kLayerRatio);
}

// The same peak where every layer moved 3.6 % further (the vehicle sped up): the other layers
// keep its ratio, and it is the followed layer's. With a single other layer nothing refutes it.
TEST(SteadyLayerStep, APeakTheOtherLayersKeepPaceWithStands) {
  constexpr double kFaster = 114.0 / 110.0;
  LengthSource source = LengthSource::kNone;
  const PairMotion faster = detail::steadyLayerStep(
      motionAlongX(132.5 * kFaster), withPeaks({{92.7 * kFaster, 1.0}, {114.0, 0.3}, {132.5 * kFaster, 0.5}}),
      threeLevels01(), 110.0, EstimatorConfig(), kShiftPerBin, 1.0, &source);
  EXPECT_NEAR(faster.shift(), 114.0, 0.2);
  EXPECT_EQ(source, LengthSource::kEnergyPeak);
  const PairMotion one_other = detail::steadyLayerStep(
      motionAlongX(92.7), withPeaks({{92.7, 1.0}, {114.0, 0.3}}), energyWithPeaks({{92.7, 1.0}, {110.0, 0.6}}), 110.0,
      EstimatorConfig(), kShiftPerBin, 1.0, &source);
  EXPECT_NEAR(one_other.shift(), 114.0, 0.2);
  EXPECT_EQ(source, LengthSource::kEnergyPeak);
}

// Slow motion: a steady length inside the no-motion zone (4 x skip_bins = 20 bins here), where a
// static pattern peaks, does not hold back a speed-up.
TEST(SteadyLayerStep, SlowMotionIsLeftAlone) {
  const PairMotion step = detail::steadyLayerStep(motionAlongX(12.0), withPeaks({{6.0, 0.5}, {12.0, 1.0}}), groundAndRoofs01(),
                                                  (6.0) * 1.0, EstimatorConfig(), kShiftPerBin, 1.0);
  EXPECT_DOUBLE_EQ(step.shift(), 12.0);
}

// observe() of a pair whose followed layer was predicted (and last moved) 132 px along x, with the
// PMT reading `stretch` of that length to a relative sigma `pmt_sigma` (stretch 0: no PMT).
PairMotion observedAfter132(const RegistrationPrior& prior, double shift_sigma,
                            const PairRegistration& registration, double stretch, double pmt_sigma,
                            PairObservations* out = nullptr, double log_zoom = 0.0,
                            bool skipped_frames = false) {
  detail::Reference ref;
  ref.translation = {132.0, 0.0};
  ref.shift = 132.0;
  ref.shift_sigma = shift_sigma;
  MatchResult pmt;
  pmt.valid = stretch > 0.0;
  pmt.value = stretch;
  pmt.sigma = pmt_sigma;
  PairMotion initial;
  PairMotion measured = motionAlongX(registration.translation.x);
  measured.translation = registration.translation;  // off the x axis too (an alias off the motion)
  measured.log_zoom = log_zoom;
  measured.log_zoom_sigma = 1e-3;
  const PairObservations obs =
      detail::observe(registration, measured, pmt, MatchResult(), ref, EstimatorConfig(), kShiftPerBin, 1.0, 1.0,
                      &prior, initial, skipped_frames);
  if (out) *out = obs;
  return initial;
}

RegistrationPrior predicted132(double sigma, double radius) {
  RegistrationPrior prior;
  prior.translation = {132.0, 0.0};
  prior.translation_sigma = sigma;
  prior.translation_radius = radius;
  return prior;
}

// The roofs' pair 1-2 of a flight whose last steps spread widely (one earlier hop between layers
// left three sigmas of 24 px): the prediction of the followed roofs is 132 px, the ground's peak
// (108.9 px, the highest) lies inside that gate, the roofs' own peak (a tenth of its height)
// where they were predicted. The result of observe() for it, with the PMT's reading of the
// followed layer given by `stretch` (0: no PMT).
PairMotion observedWithStretch(double stretch, PairObservations* out = nullptr) {
  PairRegistration registration = withPeaks({{108.9, 1.0}, {132.0, 0.1}});
  registration.translation = {108.9, 0.0};
  return observedAfter132(predicted132(8.0, 60.0), 0.5, registration, stretch, 0.002, out);
}

// The PMT reads the roofs where they were predicted: the ground's peak is another layer, not a
// 17 % speed drop in one frame, however wide the gate.
TEST(ObserveFollowedLayer, ThePatternMatchKeepsTheLayerInsideAWideGate) {
  PairObservations obs;
  const PairMotion initial = observedWithStretch(1.0, &obs);
  EXPECT_NEAR(initial.shift(), 132.0, 0.5);
  EXPECT_EQ(obs.translation_use, PairObservations::TranslationUse::kDirection);
  EXPECT_EQ(obs.length_source, LengthSource::kEnergyPeak);  // the roofs' own, small peak
  EXPECT_NEAR(initial.direction(), 0.0, 1e-9);
}

// Without the PMT the gate alone decides: a peak inside it is the followed layer's (the motion
// changed). And where the PMT itself reads the shorter length, the speed did change.
TEST(ObserveFollowedLayer, APeakThePatternMatchConfirmsStands) {
  PairObservations obs;
  EXPECT_NEAR(observedWithStretch(0.0, &obs).shift(), 108.9, 1e-9);
  EXPECT_EQ(obs.translation_use, PairObservations::TranslationUse::kVector);
  EXPECT_EQ(obs.length_source, LengthSource::kPeak);
  EXPECT_NEAR(observedWithStretch(108.9 / 132.0, &obs).shift(), 108.9, 1e-9);
  EXPECT_EQ(obs.translation_use, PairObservations::TranslationUse::kVector);
}

// A neighbouring layer (a sloped roof, 5 % faster or slower) stands out in the prediction's
// window, closer to the PMT's reading than tracking.layer_gate. Where the PMT reads the followed
// layer's length to under a per cent, that peak is many of its sigmas off: the step keeps the
// followed layer's own peak. Where the PMT is as loose as the layers are close, it cannot tell
// them apart and the window's peak stands.
PairMotion observedWithNeighbour(double pmt_sigma, PairObservations* out = nullptr) {
  PairRegistration registration = withPeaks({{108.9, 1.0}, {132.0, 0.3}});
  registration.translation = {108.9, 0.0};
  registration.followed_translation = {125.9, 0.0};
  registration.followed_confidence = 1.0;
  return observedAfter132(predicted132(0.5, 40.0), 0.3, registration, 1.0, pmt_sigma, out);
}

TEST(ObserveFollowedLayer, ATightPatternMatchTellsANeighbouringLayer) {
  PairObservations obs;
  EXPECT_NEAR(observedWithNeighbour(0.008, &obs).shift(), 132.0, 0.5);
  EXPECT_EQ(obs.length_source, LengthSource::kEnergyPeak);
  EXPECT_NEAR(observedWithNeighbour(0.03, &obs).shift(), 125.9, 1e-9);
  EXPECT_EQ(obs.length_source, LengthSource::kWindowPeak);
}

// A climb over the same scene: the registration read the zoom of the highest peak's layer (the
// ground, 108.9 px), the step follows the roofs' own peak (125.9 px) in the prediction's window.
// Each layer zooms by the inverse of its depth, as it shifts: the step's zoom is the roofs', the
// ground's scaled by the peaks' ratio, not the ground's as read.
TEST(ObserveFollowedLayer, AWindowPeaksZoomIsItsLayersNotTheHighestPeaks) {
  PairRegistration registration = withPeaks({{108.9, 1.0}, {132.0, 0.3}});
  registration.translation = {108.9, 0.0};
  registration.followed_translation = {125.9, 0.0};
  registration.followed_confidence = 1.0;
  PairObservations obs;
  const double ground_zoom = 0.01;  // ln s: a climb of 1 % of the ground's depth
  const PairMotion initial =
      observedAfter132(predicted132(0.5, 40.0), 0.3, registration, 1.0, 0.03, &obs, ground_zoom);
  ASSERT_EQ(obs.length_source, LengthSource::kWindowPeak);
  ASSERT_FALSE(obs.log_zoom.empty());
  EXPECT_NEAR(obs.log_zoom.front().value, ground_zoom * 125.9 / 108.9, 1e-12);
  EXPECT_NEAR(initial.log_zoom, ground_zoom * 125.9 / 108.9, 1e-12);
  EXPECT_NEAR(obs.log_zoom.front().sigma, 1e-3 * 125.9 / 108.9, 1e-12);  // its error scales alike
  EXPECT_NEAR(initial.log_zoom_sigma, 1e-3 * 125.9 / 108.9, 1e-12);
  // Where the highest peak is the followed layer's, its zoom stands as read.
  PairRegistration roofs_highest = withPeaks({{132.0, 1.0}, {108.9, 0.3}});
  roofs_highest.translation = {132.0, 0.0};
  roofs_highest.followed_translation = roofs_highest.translation;
  roofs_highest.followed_confidence = 1.0;
  const double roof_zoom = ground_zoom * 132.0 / 108.9;
  EXPECT_NEAR(
      observedAfter132(predicted132(0.5, 40.0), 0.3, roofs_highest, 1.0, 0.03, &obs, roof_zoom).log_zoom,
      roof_zoom, 1e-12);
  EXPECT_EQ(obs.length_source, LengthSource::kPeak);
  EXPECT_NEAR(obs.log_zoom.front().value, roof_zoom, 1e-12);
}

// A periodic texture's alias is the highest peak, on the motion's direction but 2.2 times as far
// as the followed layer (no layer of the motion moves so much further): its refined zoom tells
// nothing of the followed layer's. Scaled by that ratio, its small error would have been a step
// of the altitude twice as large; the prediction's zoom stands, with both sigmas. Off the
// direction alike.
TEST(ObserveFollowedLayer, AnAliasesZoomGivesWayToThePrediction) {
  RegistrationPrior prior = predicted132(0.5, 40.0);
  prior.log_zoom = 1e-4;
  prior.log_zoom_sigma = 2e-3;
  const double alias_zoom = 0.0094;
  for (const cv::Point2d alias : {cv::Point2d(290.0, 0.0), cv::Point2d(60.0, 90.0)}) {
    PairRegistration registration = withPeaks({{132.0, 1.0}});
    registration.translation = alias;
    registration.followed_translation = {131.0, 0.0};
    registration.followed_confidence = 1.0;
    PairObservations obs;
    const PairMotion initial = observedAfter132(prior, 0.3, registration, 0.0, 0.0, &obs, alias_zoom);
    ASSERT_EQ(obs.length_source, LengthSource::kWindowPeak) << alias;
    ASSERT_FALSE(obs.log_zoom.empty());
    EXPECT_DOUBLE_EQ(obs.log_zoom.front().value, prior.log_zoom) << alias;
    EXPECT_DOUBLE_EQ(obs.log_zoom.front().sigma, std::hypot(1e-3, prior.log_zoom_sigma)) << alias;
    EXPECT_DOUBLE_EQ(initial.log_zoom, prior.log_zoom) << alias;
    EXPECT_DOUBLE_EQ(initial.log_zoom_sigma, obs.log_zoom.front().sigma) << alias;
  }
}

// The followed layer has left the view and no layer or stretch reads it: a peak on the motion
// that the vehicle could reach is taken as its change of speed, one it could not is not taken
// and the prediction's length stands. The diagnostics say which.
TEST(ObserveFollowedLayer, SaysWhetherTheSpeedChangedOrThePredictionStands) {
  PairRegistration registration = withPeaks({{150.0, 1.0}});
  registration.translation = {150.0, 0.0};
  PairObservations obs;
  EXPECT_NEAR(observedAfter132(predicted132(0.5, 30.0), 0.3, registration, 0.0, 0.0, &obs).shift(), 150.0, 1e-9);
  EXPECT_EQ(obs.length_source, LengthSource::kMotionChange);
  EXPECT_NEAR(observedAfter132(predicted132(0.5, 10.0), 0.3, registration, 0.0, 0.0, &obs).shift(), 132.0, 1e-9);
  EXPECT_EQ(obs.length_source, LengthSource::kPrediction);
  EXPECT_EQ(obs.translation_use, PairObservations::TranslationUse::kDirection);
}

// The pair's only strong peak lies 14 % beyond the predicted 132 px, on the motion and inside
// its acceleration window: a change of speed, unless the followed layer is still in view. Its
// trace at 130 px, a fiftieth of the highest peak (too small to carry a step by itself:
// tracking.steady_layer_min_fraction), is a depth layer by the energy vector's own measure
// (tracking.layer_min_fraction): the speed did not change, and the trace gives the length. A
// two-hundredth is not a layer, and the change of speed stands.
TEST(ObserveFollowedLayer, TheFollowedLayersTraceRefutesAChangeOfSpeed) {
  const EstimatorConfig config;
  ASSERT_LT(config.tracking.layer_min_fraction, 0.02);
  ASSERT_GT(config.tracking.steady_layer_min_fraction, 0.02);
  PairRegistration traced = withPeaks({{150.0, 1.0}, {130.0, 0.02}});
  traced.translation = {150.0, 0.0};
  PairObservations obs;
  EXPECT_NEAR(observedAfter132(predicted132(0.5, 30.0), 0.3, traced, 0.0, 0.0, &obs).shift(), 130.0, 0.05);
  EXPECT_EQ(obs.length_source, LengthSource::kEnergyPeak);
  EXPECT_EQ(obs.translation_use, PairObservations::TranslationUse::kDirection);
  PairRegistration untraced = withPeaks({{150.0, 1.0}, {130.0, 0.005}});
  untraced.translation = {150.0, 0.0};
  EXPECT_NEAR(observedAfter132(predicted132(0.5, 30.0), 0.3, untraced, 0.0, 0.0, &obs).shift(), 150.0, 1e-9);
  EXPECT_EQ(obs.length_source, LengthSource::kMotionChange);
}

// The same peak over a pair that spans a frame that failed: the prediction reaches twice as far
// and its acceleration window four times as wide, so a peak inside it is no reading of a change
// of speed (an alias at 56 % of the predicted two-interval length passed as one). The
// prediction's length stands, the peak's direction is kept, and the next pair over one interval
// reads the change if there was one.
TEST(ObserveFollowedLayer, NoChangeOfSpeedIsReadOverSkippedFrames) {
  PairRegistration registration = withPeaks({{150.0, 1.0}});
  registration.translation = {150.0, 0.0};
  PairObservations obs;
  const PairMotion over_skipped =
      observedAfter132(predicted132(0.5, 30.0), 0.3, registration, 0.0, 0.0, &obs, 0.0, /*skipped_frames=*/true);
  EXPECT_NEAR(over_skipped.shift(), 132.0, 1e-9);
  EXPECT_EQ(obs.length_source, LengthSource::kPrediction);
  EXPECT_EQ(obs.translation_use, PairObservations::TranslationUse::kDirection);
  EXPECT_NEAR(observedAfter132(predicted132(0.5, 30.0), 0.3, registration, 0.0, 0.0, &obs).shift(), 150.0, 1e-9);
  EXPECT_EQ(obs.length_source, LengthSource::kMotionChange);
}

// observe() of pair 1-2 after pair 0-1 moved the followed layer 132 px along x, with pair 0-1's
// translation energy vector, without PMT.
PairMotion observedAfter132With(const PairRegistration& registration, const std::vector<float>& energy01,
                                PairObservations& obs) {
  detail::Reference ref;
  ref.translation = {132.0, 0.0};
  ref.shift = 132.0;
  ref.shift_sigma = 0.3;
  ref.translation_energy = &energy01;
  PairMotion measured = motionAlongX(registration.translation.x);
  measured.log_zoom_sigma = 1e-3;
  const RegistrationPrior prior = predicted132(0.5, 30.0);
  PairMotion initial;
  obs = detail::observe(registration, measured, MatchResult(), MatchResult(), ref, EstimatorConfig(), kShiftPerBin,
                        1.0, 1.0, &prior, initial);
  return initial;
}

// The followed tops (132 px in pair 0-1, and predicted there) have left the view; the pair's
// highest peak is a wall's at 136.5 px, on the motion and inside layer_gate. The ground (92.7 px)
// and the higher tops (160 px) keep their speed: the wall's peak is another layer, and the step
// keeps the followed tops' length by the other layers' speed, along the peak's direction. Where
// every layer moved as much further, the peak is the followed layer's.
TEST(ObserveFollowedLayer, APeakInsideTheGateThatTheOtherLayersRefuteIsAnotherLayer) {
  const std::vector<float> energy01 = energyWithPeaks({{92.7, 1.0}, {132.0, 0.6}, {160.0, 0.5}});
  PairRegistration wall = withPeaks({{92.7, 0.8}, {136.5, 1.0}, {160.0, 0.5}});
  wall.translation = {136.5, 0.0};
  PairObservations obs;
  EXPECT_NEAR(observedAfter132With(wall, energy01, obs).shift(), 132.0, 0.3);
  EXPECT_EQ(obs.length_source, LengthSource::kLayerRatio);
  EXPECT_EQ(obs.translation_use, PairObservations::TranslationUse::kDirection);
  constexpr double kFaster = 136.5 / 132.0;
  PairRegistration faster = withPeaks({{92.7 * kFaster, 0.8}, {136.5, 1.0}, {160.0 * kFaster, 0.5}});
  faster.translation = {136.5, 0.0};
  EXPECT_NEAR(observedAfter132With(faster, energy01, obs).shift(), 136.5, 1e-9);
  EXPECT_EQ(obs.length_source, LengthSource::kPeak);
}

// A step of 108.9 px whose PMT stretch said 131.8 px (the roofs it followed before) and whose
// highest peak agreed with it: one reading is another layer's, and the spread says by how much.
TEST(LengthSpread, OtherReadingsInsideTheWindowWiden) {
  EXPECT_NEAR(detail::lengthSpread(108.9, {108.9, 131.8}, 0.05, 40.0), 22.9, 1e-9);
  // The largest of several; unbounded without a window.
  EXPECT_NEAR(detail::lengthSpread(100.0, {90.0, 125.0, 101.0}, 0.05, 0.0), 25.0, 1e-9);
  // Within the layers' noise (layer_gate) the readings agree.
  EXPECT_DOUBLE_EQ(detail::lengthSpread(100.0, {104.9, 95.1}, 0.05, 40.0), 0.0);
  // Beyond the acceleration window a reading is an alias the vehicle cannot have flown.
  EXPECT_DOUBLE_EQ(detail::lengthSpread(100.0, {181.8}, 0.05, 40.0), 0.0);
  EXPECT_NEAR(detail::lengthSpread(100.0, {181.8, 120.0}, 0.05, 40.0), 20.0, 1e-9);
  // Nothing to compare: no length, or readings that are not lengths.
  EXPECT_DOUBLE_EQ(detail::lengthSpread(0.0, {100.0}, 0.05, 40.0), 0.0);
  EXPECT_DOUBLE_EQ(detail::lengthSpread(100.0, {0.0, -150.0, std::nan(""), INFINITY}, 0.05, 0.0), 0.0);
  EXPECT_DOUBLE_EQ(detail::lengthSpread(100.0, {}, 0.05, 0.0), 0.0);
}

TEST(LengthSpread, WidensOnlyAlongTheStep) {
  const double direction = 0.5;
  PairMotion m;
  m.translation = cv::Point2d(std::cos(direction), std::sin(direction)) * 100.0;
  m.translation_covariance = alongAcrossCovariance(direction, 0.5, 0.3);
  const PairMotion wide = detail::withAlongTrackSpread(m, 20.0);
  EXPECT_NEAR(detail::alongTrackSigma(wide), std::hypot(0.5, 20.0), 1e-9);
  const cv::Vec2d across(-std::sin(direction), std::cos(direction));
  EXPECT_NEAR((across.t() * wide.translation_covariance * across)(0), 0.09, 1e-9);
  EXPECT_EQ(wide.translation, m.translation);
  EXPECT_EQ(detail::withAlongTrackSpread(m, 0.0).translation_covariance, m.translation_covariance);
}

// The last step before frames fail turned 0.7 degrees where the steps before it held the heading:
// the predicted frames turn at the steps' median rate, not by the last step's turn each time.
TEST(ExtrapolatedStep, TurnsAndZoomsAtTheLastStepsMedianRates) {
  std::deque<PairMotion> rates(3, motionAlongX(40.0));
  rates[0].rotation = 0.001;
  rates[0].log_zoom = 0.002;
  rates[1].rotation = -0.0005;
  rates[1].log_zoom = 0.001;
  rates[2].rotation = 0.0127;
  rates[2].log_zoom = -0.01;
  PairMotion last = rates.back();
  last.translation = {41.0, 2.0};
  const PairMotion step = detail::extrapolatedStep(last, rates);
  EXPECT_DOUBLE_EQ(step.rotation, 0.001);
  EXPECT_DOUBLE_EQ(step.log_zoom, 0.001);
  // The translation and its covariance stay the last step's.
  EXPECT_EQ(step.translation, last.translation);
  EXPECT_EQ(step.translation_covariance, last.translation_covariance);
  // Without steps that measured their rates, the last step stands whole.
  const PairMotion alone = detail::extrapolatedStep(last, {});
  EXPECT_DOUBLE_EQ(alone.rotation, last.rotation);
  EXPECT_DOUBLE_EQ(alone.log_zoom, last.log_zoom);
}

// A figure-8 flown with the heading on the track eases into its turn: 2.31, 2.53, 2.77 degrees
// per frame. The next frame turns about 3.0; the median of the three (2.53) lags a step and a
// half behind. A single wrong turn does not make a trend, and one that looks like one is bounded
// by the smaller change.
TEST(SteadilyChangingTurn, ContinuesATurnThatGrowsOrShrinksSteadily) {
  constexpr double kDeg = CV_PI / 180.0;
  std::deque<PairMotion> rates(3, motionAlongX(40.0));
  const auto turns = [&](double a, double b, double c) {
    rates[0].rotation = a * kDeg;
    rates[1].rotation = b * kDeg;
    rates[2].rotation = c * kDeg;
    return detail::steadilyChangingTurn(rates);
  };
  const std::optional<double> growing = turns(2.31, 2.53, 2.77);
  ASSERT_TRUE(growing.has_value());
  EXPECT_NEAR(*growing / kDeg, 2.97, 1e-9);  // 2.53 + 2 * 0.22
  const std::optional<double> easing = turns(-1.89, -1.70, -1.53);
  ASSERT_TRUE(easing.has_value());
  EXPECT_NEAR(*easing / kDeg, -1.36, 1e-9);  // -1.70 + 2 * 0.17
  // An outlier in the middle or first: not steady.
  EXPECT_FALSE(turns(2.3, 3.5, 2.4).has_value());
  EXPECT_FALSE(turns(3.5, 2.3, 2.4).has_value());
  // An outlier last: the smaller change continues, not the outlier's.
  EXPECT_NEAR(*turns(2.3, 2.4, 5.0) / kDeg, 2.6, 1e-9);
  // A constant turn, and fewer than three steps: the median predicts.
  EXPECT_FALSE(turns(1.0, 1.0, 1.0).has_value());
  rates.pop_front();
  EXPECT_FALSE(detail::steadilyChangingTurn(rates).has_value());
}

// A steady turn read to about 0.01 degrees, then one pair pulled 0.5 degrees off it: the outlier
// is told, and not remembered. Two in a row are a change of the yaw rate: the second stands.
TEST(RateDeviations, TellsOneOutlierTurnFromAChangeOfTheRate) {
  const double degree = CV_PI / 180.0;
  const double floor = 0.001 * degree;
  detail::RateDeviations turns(12, 6, 4.0, floor);
  const double steady[] = {0.010, -0.012, 0.006, -0.004, 0.011, -0.009, 0.008, -0.010};
  for (int k = 0; k < 5; ++k) EXPECT_FALSE(turns.outlier(steady[k] * degree)) << "too few to judge " << k;
  // Before `support` deviations are known nothing is judged, however far off.
  EXPECT_FALSE(turns.beyondGate(0.5 * degree)) << "nothing judged before the support";
  EXPECT_FALSE(turns.outlier(0.5 * degree));
  turns.clear();
  for (double d : steady) EXPECT_FALSE(turns.outlier(d * degree));
  const double spread = turns.spread();
  EXPECT_GT(spread, 0.009 * degree);
  EXPECT_LT(spread, 0.016 * degree);
  EXPECT_FALSE(turns.outlier(3.5 * spread)) << "within the gate";
  // beyondGate judges (a gyro's turn) without remembering or counting it as a step in a row.
  const double before = turns.spread();
  EXPECT_TRUE(turns.beyondGate(0.5 * degree));
  EXPECT_FALSE(turns.beyondGate(3.5 * spread));
  EXPECT_DOUBLE_EQ(turns.spread(), before);
  EXPECT_TRUE(turns.outlier(-0.5 * degree));
  EXPECT_DOUBLE_EQ(turns.spread(), spread) << "an outlier is not remembered";
  EXPECT_FALSE(turns.outlier(0.5 * degree)) << "a second one in a row is a change of the rate";
  EXPECT_TRUE(turns.outlier(-0.5 * degree)) << "after an accepted turn the gate holds again";
  // The floor: deviations of exactly zero still leave the floor's spread.
  detail::RateDeviations exact(12, 6, 4.0, floor);
  for (int k = 0; k < 6; ++k) EXPECT_FALSE(exact.outlier(0.0));
  EXPECT_DOUBLE_EQ(exact.spread(), floor);
  EXPECT_FALSE(exact.outlier(3.9 * floor));
  EXPECT_TRUE(exact.outlier(4.1 * floor));
}

// A circle over brick on every layer: the high tops (132.4 px a frame) left the view, an alias
// of theirs 4.7 % shorter stands within the layer gate, and the ratios the layers held vouch for
// 132.4 from the lower tops' peak.
constexpr double kSteady = 132.1, kVouched = 132.4, kAlias = 125.9;
constexpr double kGate = 0.05, kRatioTolerance = 0.01;

// Off pairs that did not register the followed layer itself (their step's length came from a
// weaker reading), turns beyond the gate are outliers however many come in a row, and they leave
// the record as it was: the next pair that reads its own peak is judged as if they had not been.
TEST(RateDeviations, OnlyAPairThatReadItsOwnPeakChangesTheRate) {
  const double degree = CV_PI / 180.0;
  detail::RateDeviations turns(12, 6, 4.0, 0.001 * degree);
  for (double d : {0.010, -0.012, 0.006, -0.004, 0.011, -0.009, 0.008, -0.010}) {
    EXPECT_FALSE(turns.outlier(d * degree));
  }
  const double spread = turns.spread();
  EXPECT_TRUE(turns.outlier(-0.5 * degree, false));
  EXPECT_TRUE(turns.outlier(-0.5 * degree, false)) << "a second one off a weak pair is no change";
  EXPECT_TRUE(turns.outlier(0.5 * degree, false));
  EXPECT_DOUBLE_EQ(turns.spread(), spread);
  EXPECT_FALSE(turns.outlier(3.5 * spread, false)) << "within the gate a weak pair's turn stands";
  // The weak pairs counted for nothing: a strong pair's turn beyond the gate is a first outlier,
  // the next one a change of the rate.
  EXPECT_TRUE(turns.outlier(-0.5 * degree));
  EXPECT_FALSE(turns.outlier(-0.5 * degree));
  EXPECT_TRUE(detail::lengthFromOwnPeak(LengthSource::kPeak));
  EXPECT_TRUE(detail::lengthFromOwnPeak(LengthSource::kWindowPeak));
  EXPECT_TRUE(detail::lengthFromOwnPeak(LengthSource::kMotionChange));
  EXPECT_TRUE(detail::lengthFromOwnPeak(LengthSource::kLoop));
  for (LengthSource weak : {LengthSource::kEnergyPeak, LengthSource::kLayerRatio, LengthSource::kStretch,
                            LengthSource::kPrediction, LengthSource::kVouched, LengthSource::kImplausible}) {
    EXPECT_FALSE(detail::lengthFromOwnPeak(weak));
  }
}

TEST(VouchedLength, AWeakReadingWithinTheGateGivesWayWhereTheLayersAndTheMotionAgree) {
  EXPECT_TRUE(detail::vouchedLengthWins(kAlias, LengthSource::kEnergyPeak, kVouched, kSteady, kGate, kRatioTolerance));
  EXPECT_TRUE(detail::vouchedLengthWins(kAlias, LengthSource::kLayerRatio, kVouched, kSteady, kGate, kRatioTolerance));
}

TEST(VouchedLength, TheHighestPeakOrTheFollowedLayersOwnWithinTheGateStands) {
  // The pair's own correlation peak (or the one where the prediction pointed) is a reading of its
  // own: within the gate, the vehicle may have changed its speed.
  EXPECT_FALSE(detail::vouchedLengthWins(kAlias, LengthSource::kPeak, kVouched, kSteady, kGate, kRatioTolerance));
  EXPECT_FALSE(detail::vouchedLengthWins(kAlias, LengthSource::kWindowPeak, kVouched, kSteady, kGate, kRatioTolerance));
}

TEST(VouchedLength, WithoutTheMotionsAgreementAWeakReadingWithinTheGateStands) {
  // The vouched length 3 % off the prediction: the two do not agree, nothing outweighs the step.
  EXPECT_FALSE(detail::vouchedLengthWins(kAlias, LengthSource::kEnergyPeak, kSteady * 0.97, kSteady, kGate,
                                         kRatioTolerance));
  // A step within the ratios' noise of the prediction is not moved.
  EXPECT_FALSE(detail::vouchedLengthWins(kSteady * 0.995, LengthSource::kEnergyPeak, kVouched, kSteady, kGate,
                                         kRatioTolerance));
}

TEST(VouchedLength, AStepThatBrokeAwayGivesWayButNeverTowardsAFurtherLength) {
  // Beyond the gate from the vouched length, whatever its source, towards the prediction.
  EXPECT_TRUE(detail::vouchedLengthWins(kSteady * 0.9, LengthSource::kPeak, kVouched, kSteady, kGate, kRatioTolerance));
  // A vouched length further from the prediction than the step (an alias's ratios) never wins.
  EXPECT_FALSE(detail::vouchedLengthWins(kSteady * 0.9, LengthSource::kEnergyPeak, kSteady * 0.8, kSteady, kGate,
                                         kRatioTolerance));
  EXPECT_FALSE(detail::vouchedLengthWins(kSteady, LengthSource::kEnergyPeak, 0.0, kSteady, kGate, kRatioTolerance));
}

}  // namespace
}  // namespace oefmt
