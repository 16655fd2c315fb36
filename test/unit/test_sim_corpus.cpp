// SPDX-License-Identifier: GPL-3.0-or-later
// The simulator's variety for a generalisation corpus: texture styles (natural, strictly periodic
// brick and tiles), contrast, flicker, solid blocks with walls, the spin track and climb profiles.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/error.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/renderer.h"
#include "oefmt/sim/scene.h"
#include "oefmt/sim/texture.h"
#include "oefmt/sim/track.h"

namespace oefmt {
namespace sim {
namespace {

// `texture` shifted by (dx, dy) texels with wrap-around: texture(y + dy, x + dx).
cv::Mat1f rolled(const cv::Mat1f& texture, int dx, int dy) {
  cv::Mat1f out(texture.size());
  for (int y = 0; y < texture.rows; ++y) {
    for (int x = 0; x < texture.cols; ++x) out(y, x) = texture((y + dy) % texture.rows, (x + dx) % texture.cols);
  }
  return out;
}

double maxDifference(const cv::Mat1f& a, const cv::Mat1f& b) { return cv::norm(a, b, cv::NORM_INF); }

// Mean |difference| across the wrap (last column to first, last row to first) over the mean
// |difference| of neighbours inside: about 1 for a texture without a seam.
double seamRatio(const cv::Mat1f& t) {
  double inside = 0.0, across = 0.0;
  for (int r = 0; r < t.rows; ++r) {
    for (int c = 1; c < t.cols; ++c) inside += std::fabs(t(r, c) - t(r, c - 1));
    across += std::fabs(t(r, 0) - t(r, t.cols - 1));
  }
  for (int c = 0; c < t.cols; ++c) {
    for (int r = 1; r < t.rows; ++r) inside += std::fabs(t(r, c) - t(r - 1, c));
    across += std::fabs(t(0, c) - t(t.rows - 1, c));
  }
  inside /= 2.0 * t.rows * (t.cols - 1);
  across /= t.rows + t.cols;
  return across / inside;
}

TEST(SimTexture, StylesByNameAndPerLayer) {
  EXPECT_EQ(parseEnum(kTextureStyleNames, "brick", "style"), TextureStyle::kBrick);
  EXPECT_EQ(parseEnum(kTextureStyleNames, "natural", "style"), TextureStyle::kNatural);
  EXPECT_STREQ(toString(TextureStyle::kTiles), "tiles");
  EXPECT_THROW(parseEnum(kTextureStyleNames, "marble", "style"), InputError);
  // Mixed: today's choice by layer; a list's last style serves the layers beyond it.
  EXPECT_EQ(layerTextureStyle({}, 0), TextureStyle::kCells);
  EXPECT_EQ(layerTextureStyle({}, 1), TextureStyle::kStripes);
  EXPECT_EQ(layerTextureStyle({}, 2), TextureStyle::kNoise);
  EXPECT_EQ(layerTextureStyle({}, 3), TextureStyle::kCells);
  EXPECT_EQ(layerTextureStyle({TextureStyle::kMixed}, 1), TextureStyle::kStripes);
  EXPECT_EQ(layerTextureStyle({TextureStyle::kNatural, TextureStyle::kBrick}, 0), TextureStyle::kNatural);
  EXPECT_EQ(layerTextureStyle({TextureStyle::kNatural, TextureStyle::kBrick}, 3), TextureStyle::kBrick);
  EXPECT_EQ(layerTextureStyle({TextureStyle::kNatural, TextureStyle::kMixed}, 2), TextureStyle::kNoise);
}

TEST(SimTexture, MixedStyleKeepsTodaysTextures) {
  SceneConfig config;
  config.texture_size = 128;
  config.feature_texels = 8.0;
  const Scene implicit(config);
  config.texture_styles = {TextureStyle::kMixed};
  const Scene mixed(config);
  config.texture_styles = {TextureStyle::kCells, TextureStyle::kStripes, TextureStyle::kNoise};
  const Scene spelled(config);
  ASSERT_EQ(implicit.layerCount(), 3);
  for (int layer = 0; layer < 3; ++layer) {
    EXPECT_EQ(maxDifference(implicit.texture(layer), mixed.texture(layer)), 0.0) << layer;
    EXPECT_EQ(maxDifference(implicit.texture(layer), spelled.texture(layer)), 0.0) << layer;
  }
}

TEST(SimTexture, BrickIsExactlyPeriodicRunningBondAndTiles) {
  const cv::Size brick = brickSize(64.0);
  EXPECT_EQ(brick, cv::Size(66, 22));  // about 64 long, three times as long as high, even height
  const cv::Mat1f t = brickTexture(1000, 3, 64.0);
  ASSERT_EQ(t.rows, t.cols);
  EXPECT_EQ(t.cols % (2 * brick.width), 0);  // whole periods: seamless
  EXPECT_NEAR(t.cols, 1000, brick.width);
  // Shifted by one period it is the same texture, exactly (wrap-around included).
  EXPECT_EQ(maxDifference(t, rolled(t, brick.width, 0)), 0.0);
  EXPECT_EQ(maxDifference(t, rolled(t, 0, 2 * brick.height)), 0.0);
  EXPECT_EQ(maxDifference(t, rolled(t, brick.width / 2, brick.height)), 0.0);  // running bond
  // ... but not by half a brick, or one row: those are not periods.
  EXPECT_GT(maxDifference(t, rolled(t, brick.width / 2, 0)), 0.2);
  EXPECT_GT(maxDifference(t, rolled(t, 0, brick.height)), 0.2);
  // Mortar darker than the bricks; the in-brick detail depends on the seed.
  EXPECT_LT(t(0, 0), t(brick.height / 2, brick.width / 4) - 0.2);
  EXPECT_GT(maxDifference(t, brickTexture(1000, 4, 64.0)), 0.01);
}

TEST(SimTexture, TilesAreExactlyPeriodicAndTile) {
  const int side = tileSide(64.0);
  EXPECT_EQ(side, 64);
  const cv::Mat1f t = tileTexture(1000, 3, 64.0);
  ASSERT_EQ(t.rows, t.cols);
  EXPECT_EQ(t.cols % side, 0);
  EXPECT_EQ(maxDifference(t, rolled(t, side, 0)), 0.0);
  EXPECT_EQ(maxDifference(t, rolled(t, 0, side)), 0.0);
  EXPECT_GT(maxDifference(t, rolled(t, side / 2, 0)), 0.2);
  EXPECT_GT(maxDifference(t, rolled(t, 0, side / 2)), 0.2);
  // Grout darker than the tile's face; a motif inside (the middle differs from the face).
  EXPECT_LT(t(0, 5), t(side / 4, side / 8) - 0.2);
  EXPECT_LT(t(side / 2, side / 2), t(side / 4, side / 8) - 0.15);
}

// Slope of log(radially averaged amplitude) over log(frequency), frequencies in [low, high]
// cycles per texture.
double spectralSlope(const cv::Mat1f& texture, double low, double high) {
  cv::Mat1f zero_mean = texture - cv::mean(texture)[0];
  cv::Mat2f spectrum;
  cv::dft(zero_mean, spectrum, cv::DFT_COMPLEX_OUTPUT);
  const int n = texture.rows;
  const int bins = 12;
  std::vector<double> sum(bins, 0.0);
  std::vector<int> count(bins, 0);
  for (int r = 0; r < n; ++r) {
    for (int c = 0; c < n; ++c) {
      const double f = std::hypot(r <= n / 2 ? r : r - n, c <= n / 2 ? c : c - n);
      if (f < low || f >= high) continue;
      const int bin = static_cast<int>(std::log(f / low) / std::log(high / low) * bins);
      sum[bin] += std::hypot(spectrum(r, c)[0], spectrum(r, c)[1]);
      ++count[bin];
    }
  }
  // Least-squares line through (log f, log mean amplitude) at the bins' centres.
  std::vector<double> xs, ys;
  for (int b = 0; b < bins; ++b) {
    if (count[b] == 0) continue;
    xs.push_back(std::log(low) + (b + 0.5) / bins * std::log(high / low));
    ys.push_back(std::log(sum[b] / count[b]));
  }
  const double mx = std::accumulate(xs.begin(), xs.end(), 0.0) / xs.size();
  const double my = std::accumulate(ys.begin(), ys.end(), 0.0) / ys.size();
  double sxy = 0.0, sxx = 0.0;
  for (std::size_t i = 0; i < xs.size(); ++i) {
    sxy += (xs[i] - mx) * (ys[i] - my);
    sxx += (xs[i] - mx) * (xs[i] - mx);
  }
  return sxy / sxx;
}

TEST(SimTexture, NaturalTilesSeamlesslyWithAPowerLawSpectrum) {
  const cv::Mat1f t = naturalTexture(512, 5, 512 / 40.0);
  ASSERT_EQ(t.rows, 512);
  ASSERT_EQ(t.cols, 512);
  EXPECT_NEAR(seamRatio(t), 1.0, 0.15);
  cv::Scalar mean, std;
  cv::meanStdDev(t, mean, std);
  EXPECT_NEAR(mean[0], 0.5, 0.02);
  EXPECT_NEAR(std[0], 0.15, 0.02);
  // About 1/f between the flat corner (512 / (8 * 12.8) = 5 cycles) and the finest texels.
  EXPECT_NEAR(spectralSlope(t, 12.0, 200.0), -1.0, 0.25);
  // A seam-free texture is not enough: white noise would have a flat spectrum.
  cv::Mat1f white(512, 512);
  cv::randu(white, 0.0, 1.0);
  EXPECT_NEAR(spectralSlope(white, 12.0, 200.0), 0.0, 0.1);
  // Deterministic for the seed, different for another.
  EXPECT_EQ(maxDifference(t, naturalTexture(512, 5, 512 / 40.0)), 0.0);
  EXPECT_GT(maxDifference(t, naturalTexture(512, 6, 512 / 40.0)), 0.1);
}

TEST(SimTexture, ContrastRescalesAroundMidGrey) {
  const cv::Mat1f t = withContrast(naturalTexture(256, 2, 8.0), 10.0 / 255.0);
  cv::Scalar mean, std;
  cv::meanStdDev(t, mean, std);
  EXPECT_NEAR(mean[0], 0.5, 1e-4);
  EXPECT_NEAR(std[0] * 255.0, 10.0, 0.01);
  const cv::Mat1f flat = withContrast(cv::Mat1f(16, 16, 0.8f), 0.1);  // nothing to scale
  EXPECT_EQ(cv::norm(flat - 0.5f, cv::NORM_INF), 0.0);
}

// A small flight whose frames see ground and tops; the grey std of its first 8-bit frame.
FlightOptions smallFlight() {
  FlightOptions options;
  options.width = options.height = 160;
  options.track.shape = TrackShape::kLine;
  options.track.frames = 3;
  options.track.length = 10.0;
  options.seed = 9;
  return options;
}

double firstFrameGreyStd(const FlightOptions& options) {
  const FlightPlan plan = planFlight(options);
  const Renderer renderer(std::make_shared<const Scene>(plan.scene), plan.camera, plan.supersample);
  const cv::Mat1b image = sensorImage(renderer.render(plan.poses[0]).image, plan.sensor, plan.scene.seed, 0);
  cv::Scalar mean, std;
  cv::meanStdDev(image, mean, std);
  return std[0];
}

TEST(SimRender, ContrastSetsTheFramesGreyStd) {
  FlightOptions options = smallFlight();
  const double as_made = firstFrameGreyStd(options);
  for (double contrast : {10.0, 30.0}) {
    options.contrast = contrast;
    const double measured = firstFrameGreyStd(options);
    // Bilinear sampling and supersampling smooth a little: a bit below, never above.
    EXPECT_LT(measured, contrast * 1.05) << contrast;
    EXPECT_GT(measured, contrast * 0.75) << contrast;
    EXPECT_GT(std::fabs(measured - as_made), 5.0) << contrast;  // it did change the textures
  }
  options.contrast = 10.0;
  options.texture_styles = {TextureStyle::kNatural, TextureStyle::kBrick, TextureStyle::kTiles};
  EXPECT_NEAR(firstFrameGreyStd(options), 10.0, 2.5);
  // Walls darken in proportion to the textures' contrast: a dull scene keeps dull walls.
  options.texture_styles.clear();
  options.walls = true;
  options.level_heights = {0.3 * planFlight(options).track.altitude};
  const double with_walls = firstFrameGreyStd(options);
  EXPECT_GT(with_walls, 10.0 * 0.75);
  EXPECT_LT(with_walls, 10.0 * 1.3);
  options.contrast = 200.0;
  EXPECT_THROW(planFlight(options), InputError);
}

TEST(SimSensor, FlickerGainsStayInRangeAndVary) {
  SensorOptions sensor;
  EXPECT_EQ(frameGain(sensor, 1, 7), 1.0);
  sensor.flicker = 0.1;
  std::vector<double> gains;
  for (int k = 0; k < 400; ++k) gains.push_back(frameGain(sensor, 1, k));
  const auto [low, high] = std::minmax_element(gains.begin(), gains.end());
  EXPECT_GE(*low, 0.9);
  EXPECT_LE(*high, 1.1);
  EXPECT_LT(*low, 0.91);  // the whole range is used
  EXPECT_GT(*high, 1.09);
  const double mean = std::accumulate(gains.begin(), gains.end(), 0.0) / gains.size();
  double variance = 0.0, lag_one = 0.0;
  for (std::size_t k = 0; k < gains.size(); ++k) {
    variance += (gains[k] - mean) * (gains[k] - mean);
    if (k > 0) lag_one += (gains[k] - mean) * (gains[k - 1] - mean);
  }
  EXPECT_NEAR(mean, 1.0, 0.01);
  EXPECT_NEAR(std::sqrt(variance / gains.size()), 0.1 / std::sqrt(3.0), 0.008);  // uniform
  EXPECT_LT(std::fabs(lag_one / variance), 0.15);  // independent from frame to frame
  EXPECT_EQ(frameGain(sensor, 1, 17), gains[17]);   // deterministic
  EXPECT_NE(frameGain(sensor, 2, 17), gains[17]);   // another seed, other gains
  // Times the brightness sine; the image follows the gain.
  sensor.brightness = 0.2;
  sensor.brightness_period = 40.0;
  EXPECT_NEAR(frameGain(sensor, 1, 10), 1.2 * gains[10], 1e-12);
  const cv::Mat1f grey(50, 50, 0.4f);
  EXPECT_NEAR(cv::mean(sensorImage(grey, sensor, 1, 10))[0], 255.0 * 0.4 * 1.2 * gains[10], 0.6);
}

// Every cell of every terrace carries a top of one level, 4 m high (or inclined), 3 m cells with
// the default 12 % gaps: cell (0, 0)'s top spans x, y in [0.36, 2.64].
SceneConfig blockScene(double incline_deg, bool walls) {
  SceneConfig config;
  config.levels = {{4.0, incline_deg, 1.0}};
  config.fill = 1.0;
  config.cell_size = 3.0;
  config.texture_size = 128;
  config.feature_texels = 8.0;
  config.walls = walls;
  return config;
}

// A ray from (0, 1.5, 10), above the gap west of cell (0, 0), to the point `target`.
SceneHit castTowards(const Scene& scene, const cv::Vec3d& target) {
  const cv::Vec3d origin(0.0, 1.5, 10.0);
  const cv::Vec3d d = target - origin;
  return scene.cast(origin, d / -d[2]);
}

TEST(SimWalls, ARayBesideATopHitsItsWallAtTheRightHeight) {
  const Scene walls(blockScene(0.0, true));
  // Down the gap to the west wall of cell (0, 0) at z = 2: it stays over the gap until then.
  const SceneHit hit = castTowards(walls, {0.36, 1.5, 2.0});
  EXPECT_EQ(hit.layer, 1);
  EXPECT_EQ(hit.facing, Facing::kWest);
  EXPECT_NEAR(hit.x, 0.36, 1e-9);
  EXPECT_NEAR(hit.y, 1.5, 1e-9);
  EXPECT_NEAR(hit.z, 2.0, 1e-9);
  // The level's texture along the wall and z, darker by 1.45 of its std for a west wall.
  cv::Scalar mean, std;
  cv::meanStdDev(walls.texture(1), mean, std);
  ASSERT_GT(std[0], 0.05);
  EXPECT_NEAR(walls.shade(hit), std::max(0.0, walls.sample(1, 1.5, 2.0) - 1.45 * std[0]), 1e-6);
  // Without walls the same ray passes under the top's edge to the ground.
  const SceneHit slab = castTowards(Scene(blockScene(0.0, false)), {0.36, 1.5, 2.0});
  EXPECT_EQ(slab.layer, 0);
  EXPECT_FALSE(slab.onWall());
  EXPECT_NEAR(slab.z, 0.0, 1e-9);
  // Straight down onto the top: the top, not a wall.
  const SceneHit top = walls.cast({1.5, 1.5, 10.0}, {0.0, 0.0, -1.0});
  EXPECT_EQ(top.layer, 1);
  EXPECT_FALSE(top.onWall());
  EXPECT_NEAR(top.z, 4.0, 1e-9);
  // From the east over the gap east of the top: its east wall.
  const SceneHit east = walls.cast({3.0, 1.5, 10.0}, {-0.045, 0.0, -1.0});
  EXPECT_EQ(east.facing, Facing::kEast);
  EXPECT_NEAR(east.z, 10.0 - 0.36 / 0.045, 1e-9);
  // From the south over the gap south of the top: its south wall.
  const SceneHit south = walls.cast({1.5, 0.0, 10.0}, {0.0, 0.045, -1.0});
  EXPECT_EQ(south.facing, Facing::kSouth);
  EXPECT_NEAR(south.y, 0.36, 1e-9);
}

TEST(SimWalls, InclinedTopsWallsEndAtTheirSlopingEdge) {
  const Scene scene(blockScene(20.0, true));
  double edge = 0.0;
  ASSERT_EQ(scene.layerAt(0.36 + 1e-9, 1.5, &edge), 1);
  ASSERT_GT(std::fabs(edge - 4.0), 0.05);  // the slope moves this edge off the level's height
  const SceneHit below = castTowards(scene, {0.36, 1.5, edge - 0.05});
  EXPECT_TRUE(below.onWall());
  EXPECT_NEAR(below.z, edge - 0.05, 1e-9);
  const SceneHit above = castTowards(scene, {0.36, 1.5, edge + 0.05});
  EXPECT_FALSE(above.onWall());  // over the edge: onto the sloping top
  EXPECT_EQ(above.layer, 1);
  EXPECT_GT(above.x, 0.36);
}

TEST(SimWalls, StrongParallaxFramesShowWallsOnlyWithWalls) {
  FlightOptions options = smallFlight();
  options.track.altitude = 12.0;
  options.level_heights = {0.4 * 12.0};
  options.supersample = 1;
  const auto wallPixels = [](const FlightOptions& o) {
    const FlightPlan plan = planFlight(o);
    const Renderer renderer(std::make_shared<const Scene>(plan.scene), plan.camera, 1);
    const cv::Mat1b layers = renderer.render(plan.poses[0]).layers;
    return static_cast<double>(cv::countNonZero(layers == RenderedFrame::kWallLayers + 1)) / layers.total();
  };
  EXPECT_EQ(wallPixels(options), 0.0);
  options.walls = true;
  const double share = wallPixels(options);
  EXPECT_GT(share, 0.03);
  EXPECT_LT(share, 0.5);
}

TEST(SimTrack, SpinKeepsThePositionAndTurnsByTheRate) {
  TrackConfig config;
  config.shape = TrackShape::kSpin;
  config.frames = 100;
  config.altitude = 20.0;
  config.yaw = 0.3;
  for (double rate_deg : {6.0, -13.0}) {
    config.spin_rate = rate_deg * CV_PI / 180.0;
    const std::vector<FlightPose> poses = makeTrack(config);
    ASSERT_EQ(poses.size(), 100u);
    EXPECT_NEAR(poses[0].yaw, 0.3, 1e-12);
    for (std::size_t k = 0; k < poses.size(); ++k) {
      EXPECT_EQ(poses[k].position, cv::Vec3d(0.0, 0.0, 20.0)) << k;
      if (k > 0) {
        EXPECT_NEAR(std::remainder(poses[k].yaw - poses[k - 1].yaw - config.spin_rate, 2.0 * CV_PI), 0.0, 1e-9) << k;
      }
    }
  }
  EXPECT_EQ(frameSpacing(config), 0.0);
  config.climb = 2.0;
  EXPECT_THROW(makeTrack(config), InputError);
  config.climb = 0.0;
  config.heading = HeadingMode::kTrack;
  EXPECT_THROW(makeTrack(config), InputError);
}

TEST(SimFlightPlan, SpinFliesAtItsAltitudeWithScalesFromIt) {
  FlightOptions options;
  options.track.shape = TrackShape::kSpin;
  options.track.frames = 100;
  options.track.length = 0.0;
  FlightPlan plan = planFlight(options);
  EXPECT_EQ(plan.track.altitude, kSpinAltitude);
  const double ground_pixel = kSpinAltitude / plan.camera.intrinsics.fx;
  EXPECT_NEAR(plan.scene.cell_size, 0.22 * ground_pixel * 512, 1e-9);
  EXPECT_NEAR(plan.scene.texel, 0.5 * ground_pixel, 1e-12);
  EXPECT_NEAR(plan.scene.levels[1].height, 0.3 * kSpinAltitude, 1e-9);
  // A 6 degree turn of a square view: most of it stays in view.
  EXPECT_GT(plan.ground_overlap.min, 0.85);
  EXPECT_LT(plan.ground_overlap.max, 1.0);
  options.track.altitude = 35.0;
  plan = planFlight(options);
  EXPECT_EQ(plan.poses[50].position[2], 35.0);
}

TEST(SimTrack, HillProfileOnALinePeaksHalfWayAndComesBack) {
  TrackConfig config;
  config.shape = TrackShape::kLine;
  config.length = 100.0;
  config.frames = 21;
  config.altitude = 20.0;
  config.climb = 6.0;
  config.climb_profile = ClimbProfile::kHill;
  const std::vector<FlightPose> poses = makeTrack(config);
  EXPECT_NEAR(poses[0].position[2], 20.0, 1e-12);
  EXPECT_NEAR(poses[10].position[2], 26.0, 1e-9);
  EXPECT_NEAR(poses[20].position[2], 20.0, 1e-9);
  EXPECT_NEAR(poses[5].position[2], 23.0, 1e-9);  // (1 - cos) / 2 at a quarter: half the climb
  for (int k = 1; k <= 10; ++k) EXPECT_GT(poses[k].position[2], poses[k - 1].position[2]) << k;
  EXPECT_NEAR(poses[20].position[0], 100.0, 1e-6);  // still a line along x
  // A descent: the same hill downwards, and a ramp down.
  config.climb = -6.0;
  EXPECT_NEAR(makeTrack(config)[10].position[2], 14.0, 1e-9);
  config.climb_profile = ClimbProfile::kRamp;
  EXPECT_NEAR(makeTrack(config)[20].position[2], 14.0, 1e-9);
  // Loops must come back: no ramp.
  config.shape = TrackShape::kCircle;
  EXPECT_THROW(makeTrack(config), InputError);
}

TEST(SimFlightPlan, DescentMustStayAboveTheTops) {
  FlightOptions options;
  options.track.shape = TrackShape::kLine;
  options.track.length = 200.0;
  options.track.frames = 100;
  options.track.altitude = 20.0;
  options.track.climb = -8.0;  // down to 12 m over tops up to 0.3 * 20 = 6 m (+ the incline)
  const FlightPlan plan = planFlight(options);
  EXPECT_NEAR(plan.poses.back().position[2], 12.0, 1e-9);
  options.track.altitude = 0.0;  // chosen by the overlap, above the descent
  EXPECT_GT(planFlight(options).poses.back().position[2], 0.0);
  options.track.altitude = 20.0;
  options.track.climb = -15.0;  // down to 5 m
  try {
    planFlight(options);
    ADD_FAILURE() << "a descent below the tops was accepted";
  } catch (const InputError& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find("lowest altitude (5.00 m"), std::string::npos) << message;
    EXPECT_NE(message.find("descending 15.00 m from 20.00 m"), std::string::npos) << message;
    EXPECT_NE(message.find("descend less"), std::string::npos) << message;
  }
}

TEST(SimFlightPlan, BricksAndTilesRepeatManyTimesPerImage) {
  FlightOptions options = smallFlight();
  options.width = options.height = 512;
  options.texture_styles = {TextureStyle::kBrick, TextureStyle::kTiles};
  const FlightPlan plan = planFlight(options);
  const double mean_altitude = plan.track.altitude;  // a level line
  ASSERT_EQ(plan.scene.pattern_texels.size(), plan.scene.levels.size() + 1);
  for (int layer = 0; layer <= static_cast<int>(plan.scene.levels.size()); ++layer) {
    const double depth = mean_altitude - (layer == 0 ? 0.0 : plan.scene.levels[layer - 1].height);
    const double pattern = plan.scene.patternTexels(layer);
    const double period_m = (layer == 0 ? brickSize(pattern).width : tileSide(pattern)) * plan.scene.texel;
    const double image_width_m = depth / plan.camera.intrinsics.fx * 512;
    EXPECT_GT(period_m, image_width_m / 20.0) << layer;
    EXPECT_LT(period_m, image_width_m / 12.0) << layer;
  }
}

}  // namespace
}  // namespace sim
}  // namespace oefmt
