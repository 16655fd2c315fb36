// SPDX-License-Identifier: GPL-3.0-or-later
// registration.refine_zoom: the log-polar surface reads a fraction of a bin towards the
// nearest bin (a climb of a few per mille per frame reads as half of it); the refinement on the
// intensities reads it whole.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <vector>

#include "estimation/estimator_measurements.h"
#include "oefmt/error.h"
#include "oefmt/estimation/estimator.h"
#include "oefmt/registration/pattern_matching.h"
#include "oefmt/registration/registration.h"
#include "oefmt/registration/similarity_refinement.h"
#include "oefmt/registration/window.h"
#include "oefmt/sim/similarity_views.h"
#include "support/fixtures.h"
#include "support/flight_fixtures.h"

namespace oefmt {
namespace {

constexpr int kN = 512;

PairRegistration registerWith(bool refine, const test::ImagePair& pair) {
  RegistrationConfig config;
  config.size = kN;
  config.fft_planning = FftPlanning::kEstimate;
  config.refine_zoom = refine;
  Registrar registrar(config);
  return registrar.registerPair(registrar.analyse(pair.older), registrar.analyse(pair.newer),
                                RegistrationMethod::kEnergyVectors);
}

double logZoomPerBin() {
  RegistrationConfig config;
  config.size = kN;
  config.fft_planning = FftPlanning::kEstimate;
  return Registrar(config).logZoomPerBin();
}

sim::ViewMotion motionOf(double zoom_bins, double rotation_bins, double log_zoom_per_bin) {
  sim::ViewMotion motion;
  motion.zoom = std::exp(zoom_bins * log_zoom_per_bin);
  motion.rotation = rotation_bins * CV_PI / kN;
  motion.shift = {9.5, -14.25};
  return motion;
}

TEST(ZoomRefinement, SubBinZoomsAreReadWhole) {
  const double per_bin = logZoomPerBin();
  double unrefined_worst = 0.0;
  for (double bins : {0.1, 0.2, 0.3, -0.25, 0.5, 1.3}) {
    const auto pair = test::warpedPair(motionOf(bins, 0.0, per_bin), kN, 5);
    const PairRegistration refined = registerWith(true, pair);
    const PairRegistration plain = registerWith(false, pair);
    ASSERT_EQ(refined.status, RegistrationStatus::kOk) << bins;
    ASSERT_EQ(plain.status, RegistrationStatus::kOk) << bins;
    EXPECT_TRUE(refined.zoom_refined) << bins;
    EXPECT_FALSE(plain.zoom_refined) << bins;
    EXPECT_NEAR(std::log(refined.zoom) / per_bin, bins, 0.03) << bins;
    // The rotation and the translation stay the spectral registration's.
    EXPECT_DOUBLE_EQ(refined.rotation, plain.rotation) << bins;
    EXPECT_DOUBLE_EQ(refined.translation.x, plain.translation.x) << bins;
    EXPECT_DOUBLE_EQ(refined.translation.y, plain.translation.y) << bins;
    unrefined_worst = std::max(unrefined_worst, std::fabs(std::log(plain.zoom) / per_bin - bins));
  }
  // The premise: without the refinement some zoom is read nearly a tenth of a bin off, three
  // times the refined tolerance.
  EXPECT_GT(unrefined_worst, 0.09);
}

TEST(ZoomRefinement, ARotationDoesNotBiasTheZoom) {
  // The rotation is refined along with the zoom (and not taken): a sub-bin turn the surface
  // reads short leaves the zoom right.
  const double per_bin = logZoomPerBin();
  for (double rotation_bins : {0.15, -0.35, 2.6}) {
    const auto pair = test::warpedPair(motionOf(0.2, rotation_bins, per_bin), kN, 6);
    const PairRegistration refined = registerWith(true, pair);
    ASSERT_EQ(refined.status, RegistrationStatus::kOk) << rotation_bins;
    EXPECT_TRUE(refined.zoom_refined) << rotation_bins;
    EXPECT_NEAR(std::log(refined.zoom) / per_bin, 0.2, 0.03) << rotation_bins;
    EXPECT_NEAR(refined.rotation * kN / CV_PI, rotation_bins, 0.5) << rotation_bins;
  }
}

TEST(ZoomRefinement, TheRefinementReadsSubBinRotationsToo) {
  // refineSimilarity itself: the rotation it reads is right on one plane (the registrar does not
  // take it, see registration.cpp).
  const double per_bin = logZoomPerBin();
  const SeparableWindow window(kN, RegistrationConfig{}.taper_fraction);
  for (double rotation_bins : {0.15, -0.35}) {
    const auto pair = test::warpedPair(motionOf(0.2, rotation_bins, per_bin), kN, 6);
    ImageSimilarity start;
    start.translation = {9.5, -14.25};
    const SimilarityRefinement refined =
        refineSimilarity(makeRefinementImage(pair.older), makeRefinementImage(pair.newer), start,
                         window.taper(), 3, 6);
    EXPECT_NEAR(refined.similarity.rotation * kN / CV_PI, rotation_bins, 0.03) << rotation_bins;
    EXPECT_NEAR(refined.similarity.log_zoom / per_bin, 0.2, 0.03) << rotation_bins;
    EXPECT_LT(refined.residual_end, refined.residual_start) << rotation_bins;
  }
}

// Two depth layers, each moved by its own similarity: the followed one (the start's shift) holds
// `followed_share` of the pixels; the other is shifted 15 px further and zoomed 1.5 bins more
// (roofs, a frame's step later).
struct TwoLayerPair {
  cv::Mat1f older, newer;
  sim::ViewMotion followed, other;
};

TwoLayerPair twoLayerPair(double followed_share, double per_bin) {
  const cv::Mat1f& ground = test::sceneTexture(8);
  const cv::Mat1f& roofs = test::sceneTexture(9);
  const cv::Point2d centre(ground.cols / 2.0, ground.rows / 2.0);
  // Roof blocks over the ground, a fixed pattern on the texture that moves with the roofs.
  const cv::Mat1f roof_mask = sim::blockMask(ground.size(), 5, 40.0, 1.0 - followed_share);
  TwoLayerPair pair;
  pair.followed = motionOf(0.4, 0.0, per_bin);
  pair.other = motionOf(1.9, 0.0, per_bin);
  pair.other.shift += cv::Point2d(15.0, 0.0);
  auto view = [&](const sim::ViewMotion& ground_motion, const sim::ViewMotion& roof_motion) {
    const cv::Mat1f g = sim::renderView(ground, centre, ground_motion, kN);
    const cv::Mat1f r = sim::renderView(roofs, centre, roof_motion, kN);
    const cv::Mat1f m = sim::renderView(roof_mask, centre, roof_motion, kN);
    cv::Mat1f out(kN, kN);
    for (int y = 0; y < kN; ++y) {
      for (int x = 0; x < kN; ++x) out(y, x) = m(y, x) > 0.5f ? r(y, x) : g(y, x);
    }
    return out;
  };
  pair.older = view(sim::ViewMotion{}, sim::ViewMotion{});
  pair.newer = view(pair.followed, pair.other);
  return pair;
}

TEST(ZoomRefinement, FollowsItsLayerWhereTheOtherHoldsMostPixels) {
  // The start is the followed layer's shift and a zoom read 0.3 bins short; the refinement reads
  // that layer's zoom and is taken, also where the other layer holds most of the pixels.
  const double per_bin = logZoomPerBin();
  const SeparableWindow window(kN, RegistrationConfig{}.taper_fraction);
  for (double share : {0.6, 0.4}) {
    const TwoLayerPair pair = twoLayerPair(share, per_bin);
    ImageSimilarity start;
    start.translation = pair.followed.shift;
    start.log_zoom = std::log(pair.followed.zoom) - 0.3 * per_bin;  // a spectral read, off by 0.3 bins
    const SimilarityRefinement refined = refineSimilarity(
        makeRefinementImage(pair.older), makeRefinementImage(pair.newer), start, window.taper(), 2,
        static_cast<int>(std::lround(kN / std::sqrt(3000.0))));
    EXPECT_NEAR(refined.similarity.log_zoom / per_bin, std::log(pair.followed.zoom) / per_bin, 0.05) << share;
    EXPECT_LE(refined.loss_end, refined.loss_start) << share;
    EXPECT_GE(refined.loss_end, 0.0) << share;
  }
}

TEST(ZoomRefinement, BrightnessChangeAndNoiseKeepTheZoom) {
  const double per_bin = logZoomPerBin();
  const double bins = 0.3;
  test::ImagePair pair = test::warpedPair(motionOf(bins, 0.0, per_bin), kN, 7);
  // Sensor noise of a fifth of the texture's contrast, 10 % more gain and a brighter level.
  cv::Scalar mean, deviation;
  cv::meanStdDev(pair.newer, mean, deviation);
  cv::Mat1f noise(pair.newer.size());
  cv::RNG rng(3);
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 0.2 * deviation[0]);
  pair.newer = pair.newer * 1.1 + noise + 0.1 * mean[0];
  const PairRegistration refined = registerWith(true, pair);
  ASSERT_EQ(refined.status, RegistrationStatus::kOk);
  EXPECT_TRUE(refined.zoom_refined);
  EXPECT_NEAR(std::log(refined.zoom) / per_bin, bins, 0.03);
}

TEST(ZoomRefinement, TheRefinedZoomsSigmaFollowsTheNoiseAndCoversItsError) {
  // The surface's peak width is the same whatever the noise; the refinement's normal equations
  // are not. The estimator takes the refined zoom with that sigma, calibrated
  // (uncertainty.refined_log_zoom_scale), and the slope correction it did not take.
  const double per_bin = logZoomPerBin();
  const double bins = 0.3;
  const UncertaintyConfig uncertainty;
  double sigma_clean = 0.0, sigma_noisy = 0.0;
  int pairs = 0;
  for (const double noise : {0.0, 1.0}) {
    for (const unsigned seed : {7u, 8u, 9u}) {
      test::ImagePair pair = test::warpedPair(motionOf(bins, 0.0, per_bin), kN, seed);
      cv::Scalar mean, deviation;
      cv::meanStdDev(pair.newer, mean, deviation);
      cv::Mat1f grain(pair.newer.size());
      cv::RNG rng(seed);
      rng.fill(grain, cv::RNG::NORMAL, 0.0, noise * deviation[0]);
      pair.newer = pair.newer + grain;
      const PairRegistration r = registerWith(true, pair);
      ASSERT_EQ(r.status, RegistrationStatus::kOk) << noise << " " << seed;
      ASSERT_TRUE(r.zoom_refined) << noise << " " << seed;
      ASSERT_GT(r.refined_log_zoom_sigma, 0.0) << noise << " " << seed;
      const PairMotion m = detail::calibrated(r, uncertainty);
      // With the part of the stretch's slope correction left out (none taken: no prediction), and
      // at least the estimator's floor (1e-5).
      const double sigma =
          std::hypot(r.refined_log_zoom_sigma * uncertainty.refined_log_zoom_scale, r.slope_log_zoom_sigma);
      EXPECT_DOUBLE_EQ(m.log_zoom_sigma, std::max(sigma, 1e-5));
      const double error = std::fabs(std::log(r.zoom) - bins * per_bin);
      if (noise > 0.0) {
        // Three calibrated sigmas: a normal error lies within them all but once in 370.
        EXPECT_LT(error, 3.0 * m.log_zoom_sigma) << seed;
      } else {
        // Without noise the images' interpolation is what is left, a hundredth of a bin, below
        // what the normal equations see (rendered flights always carry some noise).
        EXPECT_LT(error, 0.02 * per_bin) << seed;
      }
      (noise > 0.0 ? sigma_noisy : sigma_clean) += r.refined_log_zoom_sigma;
      ++pairs;
    }
  }
  EXPECT_EQ(pairs, 6);
  // Noise as strong as the texture: the zoom is pinned less closely.
  EXPECT_GT(sigma_noisy, 2.0 * sigma_clean);
  // And far more closely than the surface's peak width says (about a per cent).
  EXPECT_LT(sigma_noisy / 3.0 * uncertainty.refined_log_zoom_scale, 2e-3);
}

// A frame of weak texture (grey std 10 of 255 about mid grey) whose exposure changed: every grey
// level, the mean too, 10 % brighter or darker.
cv::Mat1f weakTexture(const cv::Mat1f& image, double gain) {
  cv::Scalar mean, deviation;
  cv::meanStdDev(image, mean, deviation);
  cv::Mat1f out = (image - mean[0]) * (10.0 / 255.0 / deviation[0]) + 0.5;
  return out * gain;
}

TEST(ZoomRefinement, AnExposureChangeOnWeakTextureKeepsTheLayersZoom) {
  // Two depth layers of weak texture, and the exposure's change of the mean (13 grey levels)
  // exceeds the texture's contrast. The refinement starts from the frames' mean difference: a
  // start that left it in the residuals would read their scale from it, the robust weights would
  // then keep the other layer, and the steps would fit both layers' compromise.
  const double per_bin = logZoomPerBin();
  const SeparableWindow window(kN, RegistrationConfig{}.taper_fraction);
  const int stride = static_cast<int>(std::lround(kN / std::sqrt(3000.0)));
  const TwoLayerPair pair = twoLayerPair(0.6, per_bin);
  for (double gain : {1.1, 0.9}) {
    ImageSimilarity start;
    start.translation = pair.followed.shift;
    start.log_zoom = std::log(pair.followed.zoom) - 0.3 * per_bin;  // a spectral read, off by 0.3 bins
    const SimilarityRefinement refined =
        refineSimilarity(makeRefinementImage(weakTexture(pair.older, 1.0)),
                         makeRefinementImage(weakTexture(pair.newer, gain)), start, window.taper(), 2, stride);
    EXPECT_NEAR(refined.similarity.log_zoom / per_bin, std::log(pair.followed.zoom) / per_bin, 0.02) << gain;
    EXPECT_LE(refined.loss_end, refined.loss_start) << gain;
  }
}

// Weak texture (grey std 10 of 255) under sensor noise of 5 grey levels in both frames.
void weakAndNoisy(cv::Mat1f& older, cv::Mat1f& newer, unsigned seed) {
  older = weakTexture(older, 1.0);
  newer = weakTexture(newer, 1.0);
  cv::RNG rng(seed);
  cv::Mat1f noise(older.size());
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 5.0 / 255.0);
  older += noise;
  rng.fill(noise, cv::RNG::NORMAL, 0.0, 5.0 / 255.0);
  newer += noise;
}

TEST(ZoomRefinement, KnownSensorNoiseDoesNotShortenTheSteps) {
  // Weak texture under sensor noise of half its contrast: the gradients' noise inflates the
  // normal equations and each step falls short of the zoom by a fraction. With the frames' noise
  // variance known (as FrameSpectra estimate it) the steps reach it.
  const double per_bin = logZoomPerBin();
  const SeparableWindow window(kN, RegistrationConfig{}.taper_fraction);
  const int stride = static_cast<int>(std::lround(kN / std::sqrt(3000.0)));
  const sim::ViewMotion motion = motionOf(0.4, 0.0, per_bin);
  const double noise = 5.0 / 255.0;
  double worst_known = 0.0, worst_unknown = 0.0;
  for (unsigned seed : {11u, 12u, 13u}) {
    test::ImagePair pair = test::warpedPair(motion, kN, seed);
    cv::Mat1f older = pair.older, newer = pair.newer;
    weakAndNoisy(older, newer, seed);
    ImageSimilarity start;
    start.translation = motion.shift;
    start.log_zoom = std::log(motion.zoom) - 0.5 * per_bin;
    const auto errorBins = [&](double variance) {
      const SimilarityRefinement refined =
          refineSimilarity(makeRefinementImage(older, variance), makeRefinementImage(newer, variance), start,
                           window.taper(), 2, stride);
      return std::fabs(refined.similarity.log_zoom - std::log(motion.zoom)) / per_bin;
    };
    worst_known = std::max(worst_known, errorBins(noise * noise));
    worst_unknown = std::max(worst_unknown, errorBins(0.0));
  }
  EXPECT_LT(worst_known, 0.05);
  EXPECT_GT(worst_unknown, 2.0 * worst_known);  // the premise
}

TEST(ZoomRefinement, TheLossChangeTellsABetterFitFromTheNoise) {
  // Weak texture under sensor noise. From a start half a bin off in zoom and one and a half in
  // rotation the fit improves far beyond the paired change's standard error; from the true
  // motion the steps only fit the noise, and the loss's change stays within a few of its
  // standard errors.
  const double per_bin = logZoomPerBin();
  const SeparableWindow window(kN, RegistrationConfig{}.taper_fraction);
  const int stride = static_cast<int>(std::lround(kN / std::sqrt(3000.0)));
  const sim::ViewMotion motion = motionOf(0.4, 0.0, per_bin);
  const double variance = (5.0 / 255.0) * (5.0 / 255.0);
  for (unsigned seed : {21u, 22u, 23u}) {
    test::ImagePair pair = test::warpedPair(motion, kN, seed);
    cv::Mat1f older = pair.older, newer = pair.newer;
    weakAndNoisy(older, newer, seed);
    const RefinementImage a = makeRefinementImage(older, variance);
    const RefinementImage b = makeRefinementImage(newer, variance);
    ImageSimilarity truth;
    truth.translation = motion.shift;
    truth.log_zoom = std::log(motion.zoom);
    ImageSimilarity off = truth;
    off.log_zoom -= 0.5 * per_bin;
    off.rotation += 1.5 * CV_PI / kN;
    const SimilarityRefinement from_off = refineSimilarity(a, b, off, window.taper(), 4, stride);
    const SimilarityRefinement from_truth = refineSimilarity(a, b, truth, window.taper(), 4, stride);
    ASSERT_GT(from_off.loss_change_sigma, 0.0) << seed;
    ASSERT_GT(from_truth.loss_change_sigma, 0.0) << seed;
    EXPECT_LT(from_off.loss_change, -5.0 * from_off.loss_change_sigma) << seed;
    EXPECT_LT(std::fabs(from_truth.loss_change), 3.0 * from_truth.loss_change_sigma) << seed;
  }
}

TEST(ZoomRefinement, LeavingTheOtherLayersBlocksOutSteadiesAWeakTexturesZoom) {
  // The simulator's default scene (ground and raised tops at 15-30 % of the altitude) in level
  // flight, weak texture (grey std 10) under sensor noise (5 grey levels) and flicker: every
  // layer's zoom is 1 between frames. A pixel of a top is no further off than a noisy one, so
  // the biweight keeps the tops and the steps fit a compromise that reads a zoom where the tops
  // happen to lie. The tops' shifts (the translation energy vector's other peaks) tell their
  // blocks apart; left out, they no longer pull the zoom.
  const sim::FlightOptions options = test::weakTextureFlight(sim::TrackShape::kCircle, 24);
  const sim::FlightPlan plan = test::plannedFlight(options, 25);
  const std::vector<cv::Mat1b> frames = test::renderPlan(plan);
  RegistrationConfig config;
  config.size = kN;
  config.fft_planning = FftPlanning::kEstimate;
  config.refine_zoom = false;  // the spectral start; refined below both ways
  Registrar registrar(config);
  const double per_bin = registrar.logZoomPerBin();
  const int stride = static_cast<int>(std::lround(kN / std::sqrt(3000.0)));
  const SeparableWindow window(kN, config.taper_fraction);
  const std::vector<float>& taper = window.taper();
  const double variance = options.sensor.noise * options.sensor.noise;
  double square_with = 0.0, square_without = 0.0;
  int pairs = 0, dropped = 0;
  FrameSpectra older = registrar.analyse(frames[0]);
  for (std::size_t k = 1; k < frames.size(); ++k) {
    FrameSpectra newer = registrar.analyse(frames[k]);
    const PairRegistration r = registrar.registerPair(older, newer, RegistrationMethod::kEnergyVectors);
    if (r.status == RegistrationStatus::kOk) {
      const std::vector<cv::Point2d> other_layers = otherLayerShifts(r, registrar.shiftPerBin());
      ImageSimilarity start;
      start.rotation = r.rotation;
      start.log_zoom = std::log(r.zoom);
      start.translation = r.translation;
      const RefinementImage a = makeRefinementImage(older.grey, variance);
      const RefinementImage b = makeRefinementImage(newer.grey, variance);
      const SimilarityRefinement with = refineSimilarity(a, b, start, taper, 2, stride, false, other_layers);
      const SimilarityRefinement without = refineSimilarity(a, b, start, taper, 2, stride);
      square_with += std::pow(with.similarity.log_zoom / per_bin, 2);
      square_without += std::pow(without.similarity.log_zoom / per_bin, 2);
      dropped += with.dropped_blocks;
      ++pairs;
    }
    older = std::move(newer);
  }
  ASSERT_GE(pairs, 20);
  const double rms_with = std::sqrt(square_with / pairs), rms_without = std::sqrt(square_without / pairs);
  EXPECT_GT(dropped, pairs);  // more than a block per pair
  // A tenth steadier at least (about a sixth on this flight, in bins of the log-polar surface).
  EXPECT_LT(rms_with, 0.9 * rms_without) << rms_with << " bins, without the blocks' test " << rms_without;
}

TEST(ZoomRefinement, AShiftThatNothingFollowsLeavesTheFitAsItWas) {
  // One layer, and a spurious other peak (a repetitive texture's alias, noise): no block fits
  // it better and none is left out; of the finer cells at most the test's false alarms are (a
  // few in a hundred), and the refinement reads what it reads without the other peak.
  const double per_bin = logZoomPerBin();
  const SeparableWindow window(kN, RegistrationConfig{}.taper_fraction);
  const int stride = static_cast<int>(std::lround(kN / std::sqrt(3000.0)));
  const sim::ViewMotion motion = motionOf(0.4, 0.0, per_bin);
  test::ImagePair pair = test::warpedPair(motion, kN, 11);
  cv::Mat1f older = pair.older, newer = pair.newer;
  weakAndNoisy(older, newer, 11);
  const double variance = (5.0 / 255.0) * (5.0 / 255.0);
  ImageSimilarity start;
  start.translation = motion.shift;
  start.log_zoom = std::log(motion.zoom) - 0.3 * per_bin;
  const RefinementImage a = makeRefinementImage(older, variance), b = makeRefinementImage(newer, variance);
  const SimilarityRefinement with =
      refineSimilarity(a, b, start, window.taper(), 2, stride, false, {motion.shift * 1.3, motion.shift * 0.5});
  const SimilarityRefinement without = refineSimilarity(a, b, start, window.taper(), 2, stride);
  EXPECT_EQ(with.dropped_blocks, 0);
  // About 19 x 19 cells at N = 512 (3 x 3 grid pixels each).
  EXPECT_LE(with.dropped_cells, 7);
  EXPECT_NEAR(with.similarity.log_zoom / per_bin, without.similarity.log_zoom / per_bin, 0.01);
  EXPECT_NEAR(with.similarity.rotation * kN / CV_PI, without.similarity.rotation * kN / CV_PI, 0.01);
}

// Ground moving 15 px along x (the followed layer) and, with `layers`, a raised top 40 % nearer
// moving 21 px and between them across the lower part of the view a wall, whose rows move by
// every shift between the two with their height; sensor noise of 5 grey levels, under which the
// biweight weighs the wall's lower rows as much as the ground.
struct WallScene {
  cv::Mat1f older, newer;
  double variance = 0.0;
  cv::Point2d step, top_step;
};

WallScene wallScene(bool layers) {
  WallScene scene;
  scene.step = {15.0, 0.0};
  scene.top_step = {21.0, 0.0};
  const cv::Mat1f& ground = test::sceneTexture(8);
  const cv::Mat1f& tops = test::sceneTexture(9);
  const cv::Mat1f& walls = test::sceneTexture(10);
  const cv::Point2d centre(ground.cols / 2.0, ground.rows / 2.0);
  const int wall_first = 330, wall_last = 470;  // rows of the newer view the wall covers
  const int heights = 12;
  const auto shifted = [&](const cv::Mat1f& texture, const cv::Point2d& shift) {
    sim::ViewMotion motion;
    motion.shift = shift;
    return sim::renderView(texture, centre, motion, kN);
  };
  scene.older = shifted(ground, {});
  scene.newer = shifted(ground, scene.step);
  if (layers) {
    const cv::Mat1f tops0 = shifted(tops, {}), tops1 = shifted(tops, scene.top_step);
    std::vector<cv::Mat1f> walls0, walls1;
    for (int h = 0; h < heights; ++h) {
      const double f = (h + 0.5) / heights;
      walls0.push_back(shifted(walls, {}));
      walls1.push_back(shifted(walls, scene.step + (scene.top_step - scene.step) * f));
    }
    for (int y = 0; y < kN; ++y) {
      for (int x = 0; x < kN; ++x) {
        const int h = std::min(heights - 1, (y - wall_first) * heights / (wall_last - wall_first + 1));
        if (x < 200 && y < 200) {
          scene.older(y, x) = tops0(y, x);
          scene.newer(y, x) = tops1(y, x);
        } else if (y >= wall_first && y <= wall_last) {
          scene.older(y, x) = walls0[h](y, x);
          scene.newer(y, x) = walls1[h](y, x);
        }
      }
    }
  }
  scene.variance = (5.0 / 255.0) * (5.0 / 255.0);
  cv::RNG rng(12);
  cv::Mat1f noise(scene.older.size());
  rng.fill(noise, cv::RNG::NORMAL, 0.0, std::sqrt(scene.variance));
  scene.older += noise;
  rng.fill(noise, cv::RNG::NORMAL, 0.0, std::sqrt(scene.variance));
  scene.newer += noise;
  return scene;
}

TEST(ZoomRefinement, AWallBetweenTheLayersDoesNotTurnTheFit) {
  // A wall on one side of the motion moves along it by more the further out it lies, as a turn
  // would move it: the fit over all pixels reads a turn; the wall's cells, which shifts between
  // the layers fit better, are left out and the turn read is the ground's (none).
  const double per_bin = logZoomPerBin();
  const SeparableWindow window(kN, RegistrationConfig{}.taper_fraction);
  const int stride = static_cast<int>(std::lround(kN / std::sqrt(3000.0)));
  const WallScene scene = wallScene(true);
  ImageSimilarity start;
  start.translation = scene.step;
  const RefinementImage a = makeRefinementImage(scene.older, scene.variance);
  const RefinementImage b = makeRefinementImage(scene.newer, scene.variance);
  const SimilarityRefinement with = refineSimilarity(a, b, start, window.taper(), 4, stride, false, {scene.top_step});
  const SimilarityRefinement without = refineSimilarity(a, b, start, window.taper(), 4, stride);
  const double bins_with = with.similarity.rotation * kN / CV_PI, bins_without = without.similarity.rotation * kN / CV_PI;
  EXPECT_GT(with.dropped_cells, 10) << with.dropped_blocks;
  EXPECT_LT(std::fabs(bins_with), 0.02) << "without the layers' shifts " << bins_without;
  EXPECT_GT(std::fabs(bins_without), 3.0 * std::fabs(bins_with)) << bins_with;
  EXPECT_NEAR(with.similarity.log_zoom / per_bin, 0.0, 0.05);
}

TEST(ZoomRefinement, TheCellsLeftOutAreLeftOutOfTheScalesAndTheLossToo) {
  // The residuals' scales and the loss that judges the fit are read on a sparser grid than the
  // steps'; the wall's and the top's cells left out of the steps are left out there too, so the
  // loss at the end is the ground's alone, as over a scene of ground only.
  const SeparableWindow window(kN, RegistrationConfig{}.taper_fraction);
  const int stride = static_cast<int>(std::lround(kN / std::sqrt(3000.0)));
  const WallScene layered = wallScene(true), flat = wallScene(false);
  ImageSimilarity start;
  start.translation = layered.step;
  const auto refine = [&](const WallScene& scene) {
    const RefinementImage a = makeRefinementImage(scene.older, scene.variance);
    const RefinementImage b = makeRefinementImage(scene.newer, scene.variance);
    return refineSimilarity(a, b, start, window.taper(), 4, stride, false, {scene.top_step});
  };
  const SimilarityRefinement with_layers = refine(layered), ground_only = refine(flat);
  ASSERT_GT(ground_only.loss_end, 0.0);
  // What is left above the ground's is the cells the test keeps (at the wall's foot and the
  // top's edges); the left-out cells read on the sparser grid would add as much again.
  EXPECT_LT(with_layers.loss_end - ground_only.loss_end, 0.07) << with_layers.loss_end << " vs " << ground_only.loss_end;
}

TEST(ZoomRefinement, AWholePairsZoomMatchedOnTheEnergyVectorsLocksTowardTheWholeBin) {
  // Why the estimator takes pair 0-2's zoom from its registration alone: pair 0-2's zoom energy
  // vector lies pair 1-2's whole zoom away from pair 0-1's, and on weak texture (grey std 10,
  // noise of 5 grey levels, flicker) the pattern matching of the two reads little of that
  // fraction of a bin (about 3 % here), while a registration's refined zoom reads such a
  // fraction whole (within 1 %). A line climbing from about 6 to 11 m: a third of a bin per
  // frame over its first frames.
  sim::FlightOptions options = test::weakTextureFlight(sim::TrackShape::kLine, 26);
  options.track.climb = 5.0;
  const sim::FlightPlan plan = test::plannedFlight(options, 23);
  const std::vector<cv::Mat1b> frames = test::renderPlan(plan);
  const EstimatorConfig config = test::simulatedFlightConfig(plan);  // as the estimator registers
  Registrar registrar(config.modeRegistration());
  const double per_bin = registrar.logZoomPerBin();
  const ShiftMatchOptions shift_options = detail::shiftOptions(config.matching);  // the estimator's
  const auto logZoom = [&](std::size_t from, std::size_t to) {  // the truth: the altitudes' ratio
    return std::log(plan.poses[from].position[2] / plan.poses[to].position[2]);
  };
  double true_shift = 0.0, matched_shift = 0.0, refined_error = 0.0, pair_zoom = 0.0;
  int triples = 0;
  for (std::size_t k = 0; k + 2 < frames.size(); k += 2) {
    const FrameSpectra f0 = registrar.analyse(frames[k]), f1 = registrar.analyse(frames[k + 1]),
                       f2 = registrar.analyse(frames[k + 2]);
    const PairRegistration r01 = registrar.registerPair(f0, f1, RegistrationMethod::kEnergyVectors);
    const PairRegistration r02 = registrar.registerPair(f0, f2, RegistrationMethod::kEnergyVectors);
    const MatchResult matched = matchShift(r01.zoom_energy, r02.zoom_energy, shift_options);
    if (r01.status != RegistrationStatus::kOk || !r01.zoom_refined || !matched.valid) continue;
    // The shift that puts pair 0-2's zoom at pair 0-1's minus the shift in bins.
    true_shift += (logZoom(k, k + 1) - logZoom(k, k + 2)) / per_bin;
    matched_shift += matched.value;
    refined_error += (std::log(r01.zoom) - logZoom(k, k + 1)) / per_bin;
    pair_zoom += logZoom(k, k + 1) / per_bin;
    ++triples;
  }
  ASSERT_GE(triples, 8);
  true_shift /= triples;
  matched_shift /= triples;
  refined_error /= triples;
  pair_zoom /= triples;
  ASSERT_GT(std::fabs(true_shift), 0.2) << "the premise: pair 1-2's zoom is a sizeable fraction of a bin";
  EXPECT_LT(std::fabs(matched_shift), 0.5 * std::fabs(true_shift))
      << "matched " << matched_shift << " of " << true_shift << " bins";
  EXPECT_LT(std::fabs(refined_error), 0.1 * std::fabs(pair_zoom))
      << "refined zoom off by " << refined_error << " of " << pair_zoom << " bins";
}

// The climb an estimator reads over the first frames of a line climbing over flat natural ground
// from 20 m, against the truth (both from the first frame) [m].
struct ReadClimb {
  double estimated = 0.0;
  double truth = 0.0;
};

ReadClimb climbOverFlatGround(bool refine) {
  sim::FlightOptions options;
  options.track.shape = sim::TrackShape::kLine;
  options.track.altitude = 20.0;
  options.track.climb = 5.0;
  options.flat = true;
  options.texture_styles = {sim::TextureStyle::kNatural};
  options.seed = 3;
  const sim::FlightPlan plan = test::plannedFlight(options, 40);
  const std::vector<cv::Mat1b> frames = test::renderPlan(plan);
  EstimatorConfig config = test::simulatedFlightConfig(plan);
  config.registration.refine_zoom = refine;
  Estimator estimator(config);
  ReadClimb climb;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const std::optional<Estimate> e = estimator.push(frames[k], plan.stamps[k]);
    if (e && k + 1 == frames.size()) climb.estimated = e->pose.z;
  }
  climb.truth = plan.poses.back().position[2] - plan.poses.front().position[2];
  return climb;
}

TEST(ZoomRefinement, AClimbReadsItsWholeAltitudeChange) {
  const ReadClimb refined = climbOverFlatGround(true);
  const ReadClimb plain = climbOverFlatGround(false);
  ASSERT_GT(refined.truth, 0.5);
  // Within a tenth.
  EXPECT_NEAR(refined.estimated / refined.truth, 1.0, 0.1) << refined.estimated << " m of " << refined.truth;
  // The premise: without the refinement the climb reads as about half of itself.
  EXPECT_LT(plain.estimated / plain.truth, 0.6) << plain.estimated << " m of " << plain.truth;
}

TEST(ZoomRefinement, FramesOfDifferentSizesAreAnError) {
  const RefinementImage small = makeRefinementImage(cv::Mat1f(64, 64, 1.0f));
  const RefinementImage large = makeRefinementImage(cv::Mat1f(128, 128, 1.0f));
  const std::vector<float> taper(128, 1.0f);
  EXPECT_THROW(refineSimilarity(small, large, ImageSimilarity{}, taper, 2, 1), InputError);
  EXPECT_THROW(refineSimilarity(large, large, ImageSimilarity{}, std::vector<float>(64, 1.0f), 2, 1),
               InputError);
  // A mask of what the camera saw must cover the frame, made here or handed in.
  EXPECT_THROW(makeRefinementImage(cv::Mat1f(128, 128, 1.0f), 0.0, cv::Mat1b(64, 64, 255)), InputError);
  RefinementImage masked = large;
  masked.seen = cv::Mat1b(64, 64, 255);
  EXPECT_THROW(refineSimilarity(large, masked, ImageSimilarity{}, taper, 2, 1), InputError);
  RegistrationConfig config;
  config.size = 128;
  config.fft_planning = FftPlanning::kEstimate;
  Registrar registrar(config);
  PreparedImage image = prepareImage(cv::Mat1f(128, 128, 0.5f), 128);
  image.seen = cv::Mat1b(64, 128, 255);
  EXPECT_THROW(registrar.analyse(image), InputError);
}

TEST(ZoomRefinement, AFlatFrameLeavesTheStartUnchanged) {
  // No gradient: the normal equations are singular and nothing is refined.
  const RefinementImage flat = makeRefinementImage(cv::Mat1f(128, 128, 40.0f));
  ImageSimilarity start;
  start.log_zoom = 0.01;
  start.rotation = 0.02;
  const SimilarityRefinement refined = refineSimilarity(flat, flat, start, std::vector<float>(128, 1.0f), 3, 1);
  EXPECT_DOUBLE_EQ(refined.similarity.log_zoom, 0.01);
  EXPECT_DOUBLE_EQ(refined.similarity.rotation, 0.02);
}

}  // namespace
}  // namespace oefmt
