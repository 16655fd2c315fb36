// SPDX-License-Identifier: GPL-3.0-or-later
// BlockMotionReader: a pair's rotation and zoom from the shifts of the blocks that follow it.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"
#include "oefmt/registration/block_motion.h"
#include "oefmt/registration/registration.h"
#include "oefmt/registration/window.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/similarity_views.h"
#include "support/fixtures.h"
#include "support/flight_fixtures.h"

namespace oefmt {
namespace {

constexpr int kN = 512;

sim::ViewMotion motion(double rotation, double log_zoom) {
  sim::ViewMotion m;
  m.rotation = rotation;
  m.zoom = std::exp(log_zoom);
  m.shift = {9.5, -14.25};
  return m;
}

ImageSimilarity startNear(const sim::ViewMotion& truth, double rotation_off, double log_zoom_off) {
  ImageSimilarity start;
  start.rotation = truth.rotation + rotation_off;
  start.log_zoom = std::log(truth.zoom) + log_zoom_off;
  start.translation = truth.shift;
  return start;
}

TEST(BlockMotion, ReadsARigidMotionFromAStartOffByPixelsAtTheEdge) {
  BlockMotionReader reader(kN, FftPlanning::kEstimate);
  EXPECT_EQ(reader.blockSize(), kN / 8);
  for (const auto& [rotation, log_zoom] : {std::pair{0.02, 0.004}, std::pair{-0.05, -0.006}, std::pair{0.0, 0.0}}) {
    const sim::ViewMotion truth = motion(rotation, log_zoom);
    const test::ImagePair pair = test::warpedPair(truth, kN, 5);
    // Four milliradians and two per mille move the image's edge by about a pixel.
    for (const double off : {0.0, 0.004, -0.004}) {
      const BlockMotion read = reader.read(pair.older, pair.newer, startNear(truth, off, 0.5 * off));
      ASSERT_TRUE(read.valid) << rotation << " " << off;
      EXPECT_GE(read.blocks, 30) << rotation << " " << off;
      EXPECT_LE(read.blocks, read.tried);
      EXPECT_NEAR(read.rotation, rotation, 2e-4) << rotation << " " << off;
      EXPECT_NEAR(read.log_zoom, log_zoom, 3e-4) << rotation << " " << off;
      // The sigmas describe the scatter: small, but not zero, and not far below the error.
      EXPECT_GT(read.rotation_sigma, 0.0);
      EXPECT_LT(read.rotation_sigma, 1e-3);
      EXPECT_GT(read.log_zoom_sigma, 0.0);
      EXPECT_LT(read.log_zoom_sigma, 1e-3);
      EXPECT_LT(std::fabs(read.rotation - rotation), 5.0 * read.rotation_sigma + 2e-5);
    }
  }
}

TEST(BlockMotion, BlocksOfAnotherMotionLeaveTheFit) {
  // A quarter of the newer frame (a raised layer) moves 12 px further than the rest: its blocks
  // lie beyond the follow radius and leave the fit. Kept, they would turn it by tens of
  // milliradians; the blocks on the seam, which hold both motions, still lean on it a little.
  const sim::ViewMotion truth = motion(0.01, 0.002);
  const test::ImagePair pair = test::warpedPair(truth, kN, 6);
  sim::ViewMotion layer = truth;
  layer.shift += cv::Point2d(12.0, 0.0);
  const test::ImagePair moved = test::warpedPair(layer, kN, 6);
  cv::Mat1f newer = pair.newer.clone();
  moved.newer(cv::Rect(0, 0, kN / 2, kN / 2)).copyTo(newer(cv::Rect(0, 0, kN / 2, kN / 2)));
  BlockMotionReader reader(kN, FftPlanning::kEstimate);
  const BlockMotion all = reader.read(pair.older, pair.newer, startNear(truth, 0.002, 0.0));
  const BlockMotion rest = reader.read(pair.older, newer, startNear(truth, 0.002, 0.0));
  ASSERT_TRUE(all.valid);
  ASSERT_TRUE(rest.valid);
  EXPECT_LT(rest.blocks, all.blocks - 6);
  // From a start 2 mrad off, a single reading takes away three quarters of the offset or more
  // (the blocks' peaks lean a little towards no shift), with the other layer's blocks or without.
  EXPECT_NEAR(all.rotation, truth.rotation, 5e-4);
  EXPECT_NEAR(rest.rotation, truth.rotation, 5e-4);
  EXPECT_NEAR(rest.rotation, all.rotation, 2e-4);
  EXPECT_NEAR(rest.log_zoom, std::log(truth.zoom), 5e-4);
}

TEST(BlockMotion, UnrelatedFramesReadNothing) {
  const test::ImagePair a = test::warpedPair(motion(0.0, 0.0), kN, 5);
  const test::ImagePair b = test::warpedPair(motion(0.0, 0.0), kN, 9);
  BlockMotionReader reader(kN, FftPlanning::kEstimate);
  const BlockMotion read = reader.read(a.older, b.newer, startNear(motion(0.0, 0.0), 0.0, 0.0));
  EXPECT_FALSE(read.valid);
  EXPECT_LT(read.blocks, 6);
}

double quantile(std::vector<double> v, double q) {
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(q * v.size()))];
}

TEST(BlockMotion, OnRoofsWithWallsTheBlocksReadTheTurnThatAnUnsettledRefinementMisses) {
  // The corpus's second strong-parallax line (line-parallax-s2): striped roofs at 40 % of the
  // altitude, their walls in view, the heading along a straight line: every pair's turn is zero.
  sim::FlightOptions options;
  options.track.shape = sim::TrackShape::kLine;
  options.track.heading = sim::HeadingMode::kTrack;
  options.track.line_direction = 30.0 * CV_PI / 180.0;
  options.track.altitude = 20.0;
  options.level_heights = {8.0};
  options.walls = true;
  options.seed = 34;
  const sim::FlightPlan plan = test::plannedFlight(options, 45);
  const std::vector<cv::Mat1b> frames = test::renderPlan(plan);
  RegistrationConfig config;
  config.fft_planning = FftPlanning::kEstimate;
  Registrar registrar(config);
  const SeparableWindow window(config.size, config.taper_fraction);
  std::vector<double> read, refined_alone;
  for (std::size_t k = 1; k < frames.size(); ++k) {
    const FrameSpectra a = registrar.analyse(frames[k - 1]), b = registrar.analyse(frames[k]);
    // A quarter turn is beyond any vehicle between frames (the stripes read as well turned by one).
    const PairRegistration r =
        registrar.registerPair(a, b, RegistrationMethod::kEnergyVectors, nullptr, nullptr, CV_PI / 4.0);
    if (!r.usable() || r.motion_blocks == 0) continue;
    // The premise: the refinement alone, from the same start, as the registration runs it.
    ImageSimilarity start;
    start.rotation = r.rotation;
    start.log_zoom = std::log(r.zoom);
    start.translation = r.translation;
    const SimilarityRefinement alone =
        refineSimilarity(a.refinement, b.refinement, start, window.taper(), 4, 9, true,
                         otherLayerShifts(r, registrar.shiftPerBin()));
    read.push_back(std::fabs(r.refined_rotation));
    refined_alone.push_back(std::fabs(alone.similarity.rotation));
  }
  ASSERT_GE(read.size(), 6u) << "pairs over the roofs leave the refinement unsettled";
  std::printf("[ block motion ] %zu unsettled pairs: |turn| median %.2f, 90th percentile %.2f mrad "
              "(the refinement alone: %.2f, %.2f)\n",
              read.size(), 1e3 * quantile(read, 0.5), 1e3 * quantile(read, 0.9), 1e3 * quantile(refined_alone, 0.5),
              1e3 * quantile(refined_alone, 0.9));
  EXPECT_GT(quantile(refined_alone, 0.9), 3e-3) << "the premise: the refinement alone misses by milliradians";
  EXPECT_LT(quantile(read, 0.9), 0.5 * quantile(refined_alone, 0.9));
  EXPECT_LT(quantile(read, 0.5), 1e-3);
}

TEST(BlockMotion, OnATurnOverRaisedLayersTheShiftsAcrossTheMotionReadTheTurn) {
  // The corpus's yawing figure-8 (eight-yaw), through its first turns: the simulator's default
  // scene (raised levels at 15 and 30 % of the altitude, and an inclined one), the heading along
  // the track. Where the refinement did not settle, the blocks of the nearer layers follow the
  // pair's shift within a pixel or two and, on one side of the view, turn a fit of both
  // components by milliradians; across the motion their shifts hold no depth.
  sim::FlightOptions options;
  options.track.shape = sim::TrackShape::kEight;
  options.track.heading = sim::HeadingMode::kTrack;
  options.track.length = 880.0;  // oefmt_simulate's figure-8
  options.track.frames = 300;
  options.seed = 7;
  sim::FlightPlan plan = test::plannedFlight(options, 74);
  constexpr int kFirst = 30;
  plan.poses.erase(plan.poses.begin(), plan.poses.begin() + kFirst);
  plan.stamps.erase(plan.stamps.begin(), plan.stamps.begin() + kFirst);
  const std::vector<cv::Mat1b> frames = test::renderPlan(plan);
  RegistrationConfig config;
  config.fft_planning = FftPlanning::kEstimate;
  Registrar registrar(config);
  const SeparableWindow window(config.size, config.taper_fraction);
  BlockMotionReader reader(config.size, FftPlanning::kEstimate);
  std::vector<double> both, across, best, registered;
  int across_taken = 0;
  for (std::size_t k = 1; k < frames.size(); ++k) {
    const FrameSpectra a = registrar.analyse(frames[k - 1]), b = registrar.analyse(frames[k]);
    const PairRegistration r = registrar.registerPair(a, b, RegistrationMethod::kEnergyVectors);
    if (!r.usable() || r.motion_blocks == 0) continue;
    // The image turns against the camera's yaw.
    const double truth = -std::remainder(plan.poses[k].yaw - plan.poses[k - 1].yaw, 2.0 * CV_PI);
    // The blocks sampled where the registration sampled them: at the refinement's similarity.
    ImageSimilarity start;
    start.rotation = r.rotation;
    start.log_zoom = std::log(r.zoom);
    start.translation = r.translation;
    ImageSimilarity at = refineSimilarity(a.refinement, b.refinement, start, window.taper(), 4, 9, true,
                                          otherLayerShifts(r, registrar.shiftPerBin()))
                             .similarity;
    at.stretch_a = at.stretch_b = 0.0;
    const BlockMotion fit_both = reader.read(a.grey, b.grey, at, BlockFit::kBoth);
    const BlockMotion fit_across = reader.read(a.grey, b.grey, at, BlockFit::kAcrossMotion);
    const BlockMotion fit_best = reader.read(a.grey, b.grey, at);
    if (!fit_both.valid || !fit_across.valid || !fit_best.valid) continue;
    EXPECT_TRUE(fit_across.across_motion);
    EXPECT_FALSE(fit_both.across_motion);
    across_taken += fit_best.across_motion ? 1 : 0;
    both.push_back(std::fabs(fit_both.rotation - truth));
    across.push_back(std::fabs(fit_across.rotation - truth));
    best.push_back(std::fabs(fit_best.rotation - truth));
    registered.push_back(std::fabs(r.refined_rotation - truth));
  }
  ASSERT_GE(best.size(), 4u) << "pairs over the raised layers leave the refinement unsettled";
  std::printf("[ block motion ] %zu unsettled pairs, |turn error| median / 90th percentile [mrad]: both "
              "components %.2f / %.2f, across the motion %.2f / %.2f, the smaller sigma's %.2f / %.2f "
              "(across in %d), registered %.2f / %.2f\n",
              best.size(), 1e3 * quantile(both, 0.5), 1e3 * quantile(both, 0.9), 1e3 * quantile(across, 0.5),
              1e3 * quantile(across, 0.9), 1e3 * quantile(best, 0.5), 1e3 * quantile(best, 0.9), across_taken,
              1e3 * quantile(registered, 0.5), 1e3 * quantile(registered, 0.9));
  EXPECT_GT(quantile(both, 0.5), 2e-3) << "the premise: the layers turn a fit of both components";
  EXPECT_LT(quantile(across, 0.5), 0.4 * quantile(both, 0.5));
  EXPECT_LT(quantile(across, 0.9), 0.4 * quantile(both, 0.9));
  EXPECT_LT(quantile(best, 0.9), 0.4 * quantile(both, 0.9));
  EXPECT_GT(across_taken, 0);
  // The registration reports the blocks' reading on these pairs.
  EXPECT_LT(quantile(registered, 0.9), 0.4 * quantile(both, 0.9));
}

TEST(BlockMotion, FramesOfAnotherSizeAreAClearError) {
  BlockMotionReader reader(kN, FftPlanning::kEstimate);
  const cv::Mat1f small(256, 256, 0.0f);
  EXPECT_THROW(reader.read(small, small, ImageSimilarity()), InputError);
  EXPECT_THROW(BlockMotionReader(48, FftPlanning::kEstimate), InputError);
  EXPECT_EQ(BlockMotionReader(74, FftPlanning::kEstimate).blockSize(), 8);
}

}  // namespace
}  // namespace oefmt
