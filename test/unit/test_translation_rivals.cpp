// SPDX-License-Identifier: GPL-3.0-or-later
// A strictly periodic texture matches itself at every period of its lattice: registered without a
// predicted translation, each of its correlation peaks is as good a reading of the motion as the
// others, and the highest may be an alias. The registration names that rival and reports a low
// confidence; a natural texture's peak has none. Where the motion so far rests on such a reading,
// a clearly better peak elsewhere wins over the prediction.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <opencv2/core.hpp>

#include "estimation/estimator_measurements.h"
#include "oefmt/estimation/estimator.h"
#include "oefmt/registration/registration.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/texture.h"
#include "support/fixtures.h"
#include "support/flight_fixtures.h"

namespace oefmt {
namespace {

constexpr int kN = 512;
const cv::Point kShift(37, 9);  // the motion of the newer view's content [px]

struct Views {
  cv::Mat1f older;
  cv::Mat1f newer;
};

// Two kN x kN views of `texture`, the newer one's content moved by `shift`.
Views shiftedViews(const cv::Mat1f& texture, cv::Point shift) {
  const cv::Point origin(texture.cols / 2 - kN / 2, texture.rows / 2 - kN / 2);
  return {texture(cv::Rect(origin, cv::Size(kN, kN))).clone(),
          texture(cv::Rect(origin - shift, cv::Size(kN, kN))).clone()};
}

// Within a quarter turn, as a vehicle's yaw rate bounds it: a brick wall also reads the same
// turned by half a turn (test_periodic_heading.cpp).
PairRegistration registerViews(const Views& views, const RegistrationPrior* prior = nullptr) {
  Registrar registrar(test::sharedContext(kN));
  const FrameSpectra older = registrar.analyse(views.older), newer = registrar.analyse(views.newer);
  return registrar.registerPair(older, newer, RegistrationMethod::kEnergyVectors, nullptr, prior, CV_PI / 4.0);
}

// A prediction of no turn and no zoom (narrow windows) and of a translation within `radius` px.
RegistrationPrior stillPriorWithShift(const cv::Point2d& translation, double radius) {
  RegistrationPrior prior;
  prior.rotation_sigma = 0.01;
  prior.log_zoom_sigma = 0.005;
  prior.rotation_window = 0.05;
  prior.log_zoom_window = 0.03;
  prior.translation = translation;
  prior.translation_radius = radius;
  prior.translation_sigma = 1.0;
  return prior;
}

TEST(TranslationRivals, APeriodicTexturesReadingWithoutAPredictionIsNotConfident) {
  const double brick_px = 60.0;
  const cv::Size brick = sim::brickSize(brick_px);
  // Half a lattice period (half a brick along, a row across): the motion and its alias one period
  // back lie as far from zero shift, and match equally well.
  const cv::Point half_period(brick.width / 4, brick.height / 2);
  const PairRegistration r = registerViews(shiftedViews(sim::brickTexture(1024, 5, brick_px), half_period));
  std::printf("[ rivals ] brick: taken (%.1f, %.1f), rival (%.1f, %.1f) at %.3f, confidence %.3f of %.3f\n",
              r.translation.x, r.translation.y, r.rival_translation.x, r.rival_translation.y, r.rival_ratio,
              r.confidence, r.peak_confidence);
  EXPECT_TRUE(r.usable()) << "the peaks stand out: the pair registers";
  EXPECT_GT(r.rival_ratio, 0.9) << "another period matches as well";
  EXPECT_LT(r.confidence, RegistrationConfig{}.min_confidence) << "which period is the motion is a guess";
  // The rival lies a whole number of lattice periods from the taken peak: rows repeat every
  // brick height, shifted by half a brick.
  const cv::Point2d apart = r.rival_translation - r.translation;
  const double rows = apart.y / brick.height;
  const double bricks = (apart.x - std::round(rows) * brick.width / 2.0) / brick.width;
  EXPECT_NEAR(rows, std::round(rows), 1.5 / brick.height);
  EXPECT_NEAR(bricks, std::round(bricks), 1.5 / brick.width);
}

TEST(TranslationRivals, ANaturalTexturesPeakHasNoRival) {
  const PairRegistration r = registerViews(shiftedViews(sim::naturalTexture(1024, 3, 48.0), kShift));
  EXPECT_NEAR(r.translation.x, kShift.x, 0.5);
  EXPECT_NEAR(r.translation.y, kShift.y, 0.5);
  EXPECT_LT(r.rival_ratio, kCompetingTranslationPeak);
  EXPECT_DOUBLE_EQ(r.uniqueness(), 1.0);
  EXPECT_DOUBLE_EQ(r.confidence, r.peak_confidence);
  EXPECT_GT(r.confidence, 0.9);
}

TEST(TranslationRivals, AnAmbiguousPredictionGivesWayToABetterPeak) {
  const Views views = shiftedViews(sim::naturalTexture(1024, 3, 48.0), kShift);
  // A prediction a brick period off (as a track that followed an alias would make), whose window
  // leaves the motion out.
  RegistrationPrior prior = stillPriorWithShift(cv::Point2d(kShift.x + 60.0, kShift.y), 20.0);
  const PairRegistration trusted = registerViews(views, &prior);
  EXPECT_FALSE(trusted.translation_unrivalled);
  EXPECT_TRUE(trusted.translation_implausible) << "a trusted prediction rules the motion out";
  EXPECT_FALSE(trusted.usable());

  prior.translation_ambiguous = true;
  const PairRegistration doubted = registerViews(views, &prior);
  EXPECT_TRUE(doubted.translation_unrivalled);
  EXPECT_TRUE(doubted.usable());
  EXPECT_NEAR(doubted.translation.x, kShift.x, 0.5);
  EXPECT_NEAR(doubted.translation.y, kShift.y, 0.5);
  EXPECT_GE(doubted.prediction_share, 0.0);
  EXPECT_LE(doubted.prediction_share, kCompetingTranslationPeak) << "the prediction's share of the highest peak";

  // Pairs since the start where the prediction's peak stood above the others keep it against
  // this one, until this pair's share and theirs together reach the competitor's share.
  const double this_pair = doubtLogShare(doubted.prediction_share);
  prior.doubt_log_share = std::log(kCompetingTranslationPeak) - this_pair + 0.1;
  const PairRegistration kept = registerViews(views, &prior);
  EXPECT_FALSE(kept.translation_unrivalled) << "the record outweighs one pair";
  prior.doubt_log_share -= 0.2;
  const PairRegistration left = registerViews(views, &prior);
  EXPECT_TRUE(left.translation_unrivalled) << "the pair outweighs the record";
  EXPECT_NEAR(left.translation.x, kShift.x, 0.5);
  prior.doubt_log_share = 0.0;

  // A doubted prediction that the highest peak, unrivalled, confirms.
  prior.translation = cv::Point2d(kShift.x + 3.0, kShift.y);
  const PairRegistration confirmed = registerViews(views, &prior);
  EXPECT_TRUE(confirmed.translation_unrivalled);
  EXPECT_NEAR(confirmed.translation.x, kShift.x, 0.5);
  EXPECT_NEAR(confirmed.translation.y, kShift.y, 0.5);
  // Where a rival as high stands in the image (a periodic texture), the doubt stays.
  const cv::Point half_period(sim::brickSize(60.0).width / 4, sim::brickSize(60.0).height / 2);
  const Views bricks = shiftedViews(sim::brickTexture(1024, 5, 60.0), half_period);
  prior.translation = cv::Point2d(half_period.x + 3.0, half_period.y);
  const PairRegistration still_doubted = registerViews(bricks, &prior);
  EXPECT_FALSE(still_doubted.translation_unrivalled);
  EXPECT_NEAR(still_doubted.translation.x, half_period.x, 0.5) << "the prediction decides";
  EXPECT_NEAR(still_doubted.translation.y, half_period.y, 0.5);
}

TEST(TranslationRivals, TheEnergyVectorIsReadAlongTheTakenPeak) {
  // Two bricks along plus a few pixels: one alias lies next to zero shift, where every direction
  // row of the polar surface passes and which is the highest value of all of them, while the
  // prediction takes the motion far out. The energy vector (the layers along the motion, which
  // the estimator's layer tests read) must be read along the taken peak's direction.
  const double brick_px = 60.0;
  const cv::Size brick = sim::brickSize(brick_px);
  const cv::Point motion(2 * brick.width + 3, 1);
  const Views views = shiftedViews(sim::brickTexture(1024, 5, brick_px), motion);
  const RegistrationPrior prior = stillPriorWithShift(cv::Point2d(motion.x + 0.5, motion.y), 8.0);
  const PairRegistration r = registerViews(views, &prior);
  ASSERT_NEAR(r.translation.x, motion.x, 0.5) << "the premise: the prediction takes the motion";
  ASSERT_NEAR(r.translation.y, motion.y, 0.5);
  const std::vector<float>& energy = r.translation_energy;
  ASSERT_FALSE(energy.empty());
  const float top = energy[static_cast<std::size_t>(test::argmax(energy))];
  const double bin = cv::norm(motion) / test::sharedContext(kN)->polarRadiusStep();
  float at_motion = 0.0f;  // the vector's highest local maximum within two bins of the motion
  for (int j = static_cast<int>(bin) - 2; j <= static_cast<int>(bin) + 3; ++j) {
    const std::size_t k = static_cast<std::size_t>(j);
    if (energy[k] >= energy[k - 1] && energy[k] >= energy[k + 1]) at_motion = std::max(at_motion, energy[k]);
  }
  // The alias next to zero shift stays the vector's highest value (every row passes it); read
  // along another row, the motion's peak would be missing altogether (about 1e-8 of it).
  std::printf("[ rivals ] the motion's peak in the energy vector: %.2g of its highest value\n", at_motion / top);
  EXPECT_GT(at_motion, 1e-3f * top) << "the taken peak stands in its own vector";
}

TEST(TranslationRivals, ARivalAsHighMakesTheStepCovarianceCoverBothReadings) {
  PairRegistration r;
  r.translation = cv::Point2d(15.0, 10.0);
  r.shift = cv::norm(r.translation);
  r.direction = std::atan2(r.translation.y, r.translation.x);
  r.shift_sigma = 0.5;
  r.direction_sigma = 0.01;
  r.rival_translation = cv::Point2d(-15.0, -10.0);
  const UncertaintyConfig uncertainty;
  const PairMotion alone = detail::calibrated(r, uncertainty);
  r.rival_ratio = 1.0;  // as high: either reading, half and half
  const PairMotion rivalled = detail::calibrated(r, uncertainty);
  const cv::Vec2d apart(-30.0, -20.0);
  const double along_rival = (apart.t() * rivalled.translation_covariance * apart)(0) / apart.dot(apart);
  const double along_alone = (apart.t() * alone.translation_covariance * apart)(0) / apart.dot(apart);
  EXPECT_NEAR(along_rival - along_alone, 0.25 * apart.dot(apart), 1e-6)
      << "two readings half and half: a variance of a quarter of their distance squared";
  r.rival_ratio = kCompetingTranslationPeak;  // no more than a competitor: the reading stands
  const PairMotion unrivalled = detail::calibrated(r, uncertainty);
  EXPECT_LT(cv::norm(unrivalled.translation_covariance - alone.translation_covariance), 1e-12);
}

TEST(TranslationRivals, AFlightThatStartsOnABrickAliasLeavesItWithinAFewFrames) {
  // A circle over brick on every layer, walls rendered: its motion runs along the bricks' rows,
  // and its first pair's highest peak is an alias one period back.
  sim::FlightOptions options;
  options.texture_styles = {sim::TextureStyle::kBrick};
  options.walls = true;
  options.seed = 42;
  constexpr int kFrames = 10;
  const sim::FlightPlan plan = test::plannedFlight(options, kFrames);
  const std::vector<cv::Mat1b> frames = test::renderPlan(plan);
  Estimator estimator(test::simulatedFlightConfig(plan));
  int left_at = -1;
  std::vector<double> ratios;  // estimated step length / true step length, after the alias
  Pose4 previous;
  for (int k = 0; k < kFrames; ++k) {
    const std::optional<Estimate> e = estimator.push(frames[k], plan.stamps[k]);
    ASSERT_TRUE(e.has_value());
    if (k == 1) {
      std::printf("[ rivals ] first pair: rival %.3f, confidence %.3f of %.3f\n", e->registration12.rival_ratio,
                  e->registration12.confidence, e->registration12.peak_confidence);
      EXPECT_GT(e->registration12.rival_ratio, 0.9) << "the premise: another period matches as well";
      EXPECT_LT(e->registration12.confidence, RegistrationConfig{}.min_confidence);
    }
    if (e->alias_left && left_at < 0) left_at = k;
    if (left_at >= 0 && k > left_at && e->state == TrackingState::kTracking) {
      const cv::Vec3d true_step = plan.poses[k].position - plan.poses[k - 1].position;
      ratios.push_back(std::hypot(e->pose.x - previous.x, e->pose.y - previous.y) /
                       std::hypot(true_step[0], true_step[1]));
      std::printf("[ rivals ] frame %d: step %.3f of the true length\n", k, ratios.back());
    }
    previous = e->pose;
  }
  std::printf("[ rivals ] the alias was left at frame %d\n", left_at);
  ASSERT_GE(left_at, 2);
  EXPECT_LE(left_at, 6) << "within a few frames";
  ASSERT_GE(ratios.size(), 2u);
  // After it the steps are the motion's (the estimator knows the true altitude: metric), not the
  // alias's, a fifth of it.
  for (const double ratio : ratios) EXPECT_NEAR(ratio, 1.0, 0.1);
}

TEST(TranslationRivals, AStartOnTheMotionIsNotLeftForAnAliasThatOutgrowsItInOnePair) {
  // A figure-8 over brick on every layer at 70 % overlap: its first pair takes the motion, with a
  // brick alias as a rival, so the start is doubted. The motion's peak stays the highest for three
  // pairs while the alias stands beside it; in the fifth pair the alias's peak is more than twice
  // the motion's. Taken then for the better reading, the alias was followed at a quarter of the
  // scale for 30 frames.
  sim::FlightOptions options;
  options.track.shape = sim::TrackShape::kEight;
  options.overlap = 0.7;
  options.texture_styles = {sim::TextureStyle::kBrick};
  options.seed = 67;
  constexpr int kFrames = 8;
  const sim::FlightPlan plan = test::plannedFlight(options, kFrames);
  const std::vector<cv::Mat1b> frames = test::renderPlan(plan);
  Estimator estimator(test::simulatedFlightConfig(plan));
  Pose4 previous, at_first;
  std::vector<double> ratios;  // estimated step length / true step length
  for (int k = 0; k < kFrames; ++k) {
    const std::optional<Estimate> e = estimator.push(frames[k], plan.stamps[k]);
    ASSERT_TRUE(e.has_value());
    if (k == 1) {
      std::printf("[ rivals ] first pair: rival %.3f\n", e->registration12.rival_ratio);
      EXPECT_GT(e->registration12.rival_ratio, kCompetingTranslationPeak) << "the premise: the start is doubted";
    }
    EXPECT_FALSE(e->alias_left) << "frame " << k;
    if (k >= 1 && e->state == TrackingState::kTracking) {
      const cv::Vec3d true_step = plan.poses[k].position - plan.poses[k - 1].position;
      ratios.push_back(std::hypot(e->pose.x - previous.x, e->pose.y - previous.y) /
                       std::hypot(true_step[0], true_step[1]));
      std::printf("[ rivals ] frame %d: step %.3f of the true length (prediction's share %.3f)\n", k,
                  ratios.back(), e->registration12.prediction_share);
    }
    if (k == 1) at_first = e->pose;
    previous = e->pose;
  }
  // The steps keep the first pair's scale (that of the layer it followed, not the ground's the
  // altitude is given for): the alias's steps would be a quarter of it. After the fifth pair the
  // alias's peak leaves the motion's too weak to register: those frames are predicted, and the
  // track goes on along the motion.
  ASSERT_GE(ratios.size(), 5u);
  for (const double ratio : ratios) EXPECT_NEAR(ratio / ratios.front(), 1.0, 0.1);
  const cv::Vec3d true_path = plan.poses[kFrames - 1].position - plan.poses[1].position;
  const double path = std::hypot(previous.x - at_first.x, previous.y - at_first.y);
  std::printf("[ rivals ] frames 1-%d: %.3f of the true distance\n", kFrames - 1,
              path / std::hypot(true_path[0], true_path[1]) / ratios.front());
  EXPECT_NEAR(path / std::hypot(true_path[0], true_path[1]) / ratios.front(), 1.0, 0.1);
}

}  // namespace
}  // namespace oefmt
