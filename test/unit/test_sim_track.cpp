// SPDX-License-Identifier: GPL-3.0-or-later
// Flight tracks (constant speed, closure, climb, heading), footprints and overlaps, flight plans.
#include <gtest/gtest.h>

#include <cmath>

#include "oefmt/error.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/track.h"

namespace oefmt {
namespace sim {
namespace {

double distance2d(const FlightPose& a, const FlightPose& b) {
  return std::hypot(a.position[0] - b.position[0], a.position[1] - b.position[1]);
}

TEST(SimTrack, CircleIsCounterClockwiseAtConstantSpeedAndCloses) {
  TrackConfig config;
  config.length = 491.0;
  config.frames = 200;
  config.altitude = 12.0;
  const std::vector<FlightPose> poses = makeTrack(config);
  ASSERT_EQ(poses.size(), 200u);
  const double radius = 491.0 / (2.0 * CV_PI);
  EXPECT_NEAR(poses[0].position[0], radius, 1e-9);
  EXPECT_NEAR(poses[0].position[1], 0.0, 1e-9);
  EXPECT_GT(poses[1].position[1], 0.0);  // counter-clockwise: first step goes north
  const double chord = 2.0 * radius * std::sin(CV_PI / 199.0);
  for (std::size_t k = 1; k < poses.size(); ++k) {
    EXPECT_NEAR(distance2d(poses[k - 1], poses[k]), chord, 1e-6) << k;
    EXPECT_NEAR(std::hypot(poses[k].position[0], poses[k].position[1]), radius, 1e-6);
    EXPECT_EQ(poses[k].position[2], 12.0);
    EXPECT_EQ(poses[k].yaw, 0.0);
  }
  EXPECT_EQ(poses.back().position, poses.front().position);  // the loop closes exactly
}

TEST(SimTrack, EightHasItsLengthAndConstantSpacing) {
  TrackConfig config;
  config.shape = TrackShape::kEight;
  config.length = 880.0;
  config.frames = 300;
  const std::vector<FlightPose> poses = makeTrack(config);
  double total = 0.0;
  const double step = frameSpacing(config);
  for (std::size_t k = 1; k < poses.size(); ++k) {
    const double d = distance2d(poses[k - 1], poses[k]);
    EXPECT_NEAR(d, step, 0.01 * step) << k;  // chords of a curved path: a little shorter
    total += d;
  }
  EXPECT_NEAR(total, 880.0, 880.0 * 0.002);
  EXPECT_EQ(poses.back().position, poses.front().position);
  // The crossing: the eight passes through the origin half-way.
  EXPECT_LT(std::hypot(poses[0].position[0], poses[0].position[1]), 1e-9);
  EXPECT_LT(std::hypot(poses[149].position[0], poses[149].position[1]), step);
}

TEST(SimTrack, LineClimbsLinearlyAlongItsDirection) {
  TrackConfig config;
  config.shape = TrackShape::kLine;
  config.length = 100.0;
  config.frames = 11;
  config.altitude = 20.0;
  config.climb = 10.0;
  config.line_direction = CV_PI / 2.0;  // north
  const std::vector<FlightPose> poses = makeTrack(config);
  for (std::size_t k = 0; k < poses.size(); ++k) {
    EXPECT_NEAR(poses[k].position[0], 0.0, 1e-9);
    EXPECT_NEAR(poses[k].position[1], 10.0 * k, 1e-6);
    EXPECT_NEAR(poses[k].position[2], 20.0 + 1.0 * k, 1e-9);
  }
}

TEST(SimTrack, ClosedTrackClimbsHalfWayAndReturns) {
  TrackConfig config;
  config.frames = 21;
  config.length = 100.0;
  config.altitude = 15.0;
  config.climb = 4.0;
  const std::vector<FlightPose> poses = makeTrack(config);
  EXPECT_NEAR(poses[10].position[2], 19.0, 1e-9);
  EXPECT_NEAR(poses[20].position[2], 15.0, 1e-9);
}

TEST(SimTrack, HeadingFollowsTheDirectionOfMotion) {
  TrackConfig config;
  config.heading = HeadingMode::kTrack;
  config.frames = 40;
  config.length = 200.0;
  const std::vector<FlightPose> poses = makeTrack(config);
  for (std::size_t k = 1; k + 1 < poses.size(); ++k) {
    const double dx = poses[k + 1].position[0] - poses[k - 1].position[0];
    const double dy = poses[k + 1].position[1] - poses[k - 1].position[1];
    EXPECT_NEAR(std::remainder(poses[k].yaw - std::atan2(dy, dx), 2.0 * CV_PI), 0.0, 1e-3) << k;
  }
}

TEST(SimTrack, RejectsInvalidConfigurations) {
  TrackConfig config;
  config.frames = 1;
  EXPECT_THROW(makeTrack(config), InputError);
  config.frames = 10;
  config.length = -1.0;
  EXPECT_THROW(makeTrack(config), InputError);
  config.length = 10.0;
  config.climb = -20.0;
  EXPECT_THROW(makeTrack(config), InputError);
  EXPECT_THROW(parseEnum(kTrackShapeNames, "square", "track"), InputError);
  EXPECT_EQ(parseEnum(kTrackShapeNames, "eight", "track"), TrackShape::kEight);
  for (const auto& entry : kTrackShapeNames) EXPECT_EQ(parseEnum(kTrackShapeNames, toString(entry.value), "track"), entry.value);
}

CameraParameters squareCamera(int size, double fx) {
  CameraParameters camera;
  camera.intrinsics = {fx, fx, (size - 1) / 2.0, (size - 1) / 2.0, size, size};
  return camera;
}

TEST(SimFootprint, OverlapOfShiftsRotationsAndZooms) {
  const CameraParameters camera = squareCamera(100, 100.0);  // footprint = altitude wide
  FlightPose a;
  a.position = {0.0, 0.0, 10.0};
  FlightPose b = a;
  b.position[0] = 2.0;  // a fifth of the 10 m footprint, along an edge
  EXPECT_NEAR(footprintOverlap(camera, a, b, 0.0), 0.8, 1e-9);
  b.position = {2.0, 2.0, 10.0};
  EXPECT_NEAR(footprintOverlap(camera, a, b, 0.0), 0.64, 1e-9);
  EXPECT_NEAR(footprintOverlap(camera, a, b, 5.0), 0.36, 1e-9);  // closer plane, smaller footprint
  b = a;
  b.yaw = CV_PI / 2.0;  // a square turned by 90 degrees covers itself
  EXPECT_NEAR(footprintOverlap(camera, a, b, 0.0), 1.0, 1e-9);
  b.yaw = 0.0;
  b.position[2] = 20.0;  // twice as high: a's footprint lies inside b's
  EXPECT_NEAR(footprintOverlap(camera, a, b, 0.0), 1.0, 1e-9);
  EXPECT_NEAR(footprintOverlap(camera, b, a, 0.0), 0.25, 1e-9);
}

TEST(SimFootprint, YawZeroImageRightIsEastAndImageUpIsNorth) {
  const CameraParameters camera = squareCamera(101, 50.0);
  FlightPose pose;
  pose.position = {3.0, 4.0, 10.0};
  const cv::Point2d right = pixelOnPlane(camera, pose, {100.0, 50.0}, 0.0);
  const cv::Point2d up = pixelOnPlane(camera, pose, {50.0, 0.0}, 0.0);
  EXPECT_NEAR(right.x, 3.0 + 10.0, 1e-9);
  EXPECT_NEAR(right.y, 4.0, 1e-9);
  EXPECT_NEAR(up.x, 3.0, 1e-9);
  EXPECT_NEAR(up.y, 4.0 + 10.0, 1e-9);
  pose.yaw = CV_PI / 2.0;  // turned left: image right now points north
  const cv::Point2d turned = pixelOnPlane(camera, pose, {100.0, 50.0}, 0.0);
  EXPECT_NEAR(turned.x, 3.0, 1e-9);
  EXPECT_NEAR(turned.y, 4.0 + 10.0, 1e-9);
}

TEST(SimFlightPlan, DefaultCircleOverlapsSeventyToEightyFivePercent) {
  const FlightPlan plan = planFlight(FlightOptions{});
  EXPECT_EQ(plan.poses.size(), 200u);
  EXPECT_EQ(plan.camera.intrinsics.width, 512);
  EXPECT_NEAR(plan.track.length, 491.0, 1e-9);
  EXPECT_GE(plan.ground_overlap.min, 0.70);
  EXPECT_LE(plan.ground_overlap.max, 0.85);
  EXPECT_NEAR(plan.ground_overlap.mean, 0.78, 0.005);
  // Three raised levels at 0.15, 0.30 and 0.225 of the altitude, the last inclined 6 degrees,
  // every terrace raised.
  ASSERT_EQ(plan.scene.levels.size(), 3u);
  EXPECT_NEAR(plan.scene.levels[0].height, 0.15 * plan.track.altitude, 1e-9);
  EXPECT_NEAR(plan.scene.levels[1].height, 0.30 * plan.track.altitude, 1e-9);
  EXPECT_NEAR(plan.scene.levels[2].height, 0.225 * plan.track.altitude, 1e-9);
  EXPECT_EQ(plan.scene.levels[0].incline_deg, 0.0);
  EXPECT_EQ(plan.scene.levels[1].incline_deg, 0.0);
  EXPECT_EQ(plan.scene.levels[2].incline_deg, 6.0);
  EXPECT_NEAR(plan.scene.levels[0].share + plan.scene.levels[1].share + plan.scene.levels[2].share, 1.0, 1e-9);
  EXPECT_DOUBLE_EQ(plan.scene.fill, 0.8);
  EXPECT_LT(plan.scene.highestTop(), plan.track.altitude);
  ASSERT_EQ(plan.stamps.size(), 200u);
  EXPECT_DOUBLE_EQ(plan.stamps[0], 1.0);
  EXPECT_DOUBLE_EQ(plan.stamps[1], 1.2);
}

TEST(SimFlightPlan, EightAndFixedAltitude) {
  FlightOptions options;
  options.track.shape = TrackShape::kEight;
  options.track.length = 880.0;
  options.track.frames = 300;
  FlightPlan plan = planFlight(options);
  EXPECT_GE(plan.ground_overlap.min, 0.70);
  EXPECT_LE(plan.ground_overlap.max, 0.86);
  options.track.altitude = 40.0;  // given: kept, overlap follows
  plan = planFlight(options);
  EXPECT_EQ(plan.track.altitude, 40.0);
  EXPECT_GT(plan.ground_overlap.mean, 0.9);
}

TEST(SimFlightPlan, FlatSceneHasOnlyTheGround) {
  FlightOptions options;
  options.flat = true;
  options.track.altitude = 2.0;  // low is fine without blocks
  const FlightPlan plan = planFlight(options);
  EXPECT_TRUE(plan.scene.levels.empty());
  EXPECT_EQ(plan.scene.highestTop(), 0.0);
}

TEST(SimFlightPlan, RejectsFlyingBelowTheBlocks) {
  FlightOptions options;
  options.track.altitude = 5.0;
  options.level_heights = {2.0, 6.0};
  EXPECT_THROW(planFlight(options), InputError);
  options.level_heights = {2.0, 3.0};
  options.overlap = 1.5;
  options.track.altitude = 0.0;
  EXPECT_THROW(planFlight(options), InputError);
}

}  // namespace
}  // namespace sim
}  // namespace oefmt
