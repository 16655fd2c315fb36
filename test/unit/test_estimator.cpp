// SPDX-License-Identifier: GPL-3.0-or-later
// The estimator on rendered flights: accuracy against their ground truth.
// World units are ground texture pixels: altitude = fx = N (see flight_fixtures.h).
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"
#include "oefmt/estimation/estimator.h"
#include "oefmt/sim/similarity_views.h"
#include "oefmt/sim/texture.h"
#include "support/fixtures.h"
#include "support/flight_fixtures.h"

namespace oefmt {
namespace {

constexpr int kN = 256;

EstimatorConfig flightConfig(EstimatorMode mode = EstimatorMode::kOefmt) {
  EstimatorConfig config;
  config.mode = mode;
  config.registration.size = kN;
  config.registration.fft_planning = FftPlanning::kEstimate;
  config.initial_altitude = kN;
  config.working_fx = kN;
  return config;
}

std::vector<Estimate> run(const test::Flight& flight, const EstimatorConfig& config) {
  Estimator estimator(config);
  std::vector<Estimate> estimates;
  for (std::size_t k = 0; k < flight.frames.size(); ++k) {
    std::optional<Estimate> e = estimator.push(flight.frames[k], static_cast<double>(k));
    EXPECT_TRUE(e.has_value());
    if (e) estimates.push_back(std::move(*e));
  }
  return estimates;
}

void expectFinite(const std::vector<Estimate>& estimates) {
  for (const Estimate& e : estimates) {
    EXPECT_TRUE(e.pose.finite()) << "frame " << e.frame_index;
    EXPECT_TRUE(e.step.finite()) << "frame " << e.frame_index;
  }
}

double travelled(const test::CameraState& s) { return std::hypot(s.east, s.north); }

// Final position error relative to the distance flown.
double relativeEndError(const std::vector<Estimate>& estimates, const test::Flight& flight) {
  const test::CameraState& truth = flight.truth.back();
  const Pose4& p = estimates.back().pose;
  return std::hypot(p.x - truth.east, p.y - truth.north) / travelled(truth);
}

TEST(Estimator, ConstantSpeedStraightLine) {
  const test::Flight flight =
      test::renderFlight(test::flightTexture(), test::straightLine(14, 7.0, -3.0), kN);
  const std::vector<Estimate> estimates = run(flight, flightConfig());
  ASSERT_EQ(estimates.size(), flight.frames.size());
  expectFinite(estimates);
  EXPECT_EQ(estimates[0].state, TrackingState::kStarted);
  EXPECT_EQ(estimates[0].length_source, LengthSource::kNone);
  for (std::size_t k = 1; k < estimates.size(); ++k) {
    const Estimate& e = estimates[k];
    EXPECT_EQ(e.state, TrackingState::kTracking) << k;
    EXPECT_EQ(e.length_source, LengthSource::kPeak) << k;  // one layer: its peak every time
    if (k < 2) continue;
    ASSERT_TRUE(e.pmt12.valid) << k;
    ASSERT_TRUE(e.pmt02.valid) << k;
    EXPECT_NEAR(e.pmt12.value, 1.0, 0.02) << k;  // lambda_12
    EXPECT_NEAR(e.pmt02.value, 2.0, 0.06) << k;  // lambda_02
    EXPECT_NEAR(e.lambda_t12, 1.0, 0.01) << k;
    EXPECT_EQ(e.loop.status, OptimizerStatus::kConverged) << k << " " << e.loop.message;
    EXPECT_LT(cv::norm(e.loop.after.translation), 0.1) << k;   // px
    EXPECT_LT(cv::norm(e.loop.before.translation), 0.5) << k;  // consistent before, too
    EXPECT_NEAR(e.loop.after.rotation, 0.0, 1e-3) << k;
    EXPECT_NEAR(e.pms12.value, 0.0, 0.2) << k;
    // The optimizer leaves consistent measurements almost unchanged.
    EXPECT_LT(cv::norm(e.step.translation - e.measured12.translation), 0.15) << k;
  }
  // Direction in the world frame: east = +x, north = +y; the scale is right.
  const Pose4& last = estimates.back().pose;
  EXPECT_GT(last.x, 0.0);
  EXPECT_LT(last.y, 0.0);
  EXPECT_LT(relativeEndError(estimates, flight), 0.01);
  EXPECT_NEAR(last.z, 0.0, 1.0);
  EXPECT_NEAR(last.yaw, 0.0, test::rad(0.3));
  // The covariance grows along the flight.
  EXPECT_GT(last.covariance(0, 0), estimates[2].pose.covariance(0, 0));
}

TEST(Estimator, SpeedChangeIsTracked) {
  std::vector<test::CameraState> states = test::straightLine(8, 0.0, 5.0);
  const std::vector<test::CameraState> faster = test::straightLine(7, 0.0, 8.0);
  for (std::size_t k = 1; k < faster.size(); ++k) {
    test::CameraState s = states.back();
    s.north += 8.0;
    states.push_back(s);
  }
  const test::Flight flight = test::renderFlight(test::flightTexture(), states, kN);
  const std::vector<Estimate> estimates = run(flight, flightConfig());
  expectFinite(estimates);
  const Estimate& change = estimates[8];  // the first pair at 8 px per frame
  EXPECT_NEAR(change.pmt12.value, 1.6, 0.04);
  EXPECT_NEAR(change.lambda_t12, 1.6, 0.02);
  EXPECT_NEAR(estimates[9].lambda_t12, 1.0, 0.02);
  EXPECT_LT(relativeEndError(estimates, flight), 0.01);
  EXPECT_GT(estimates.back().pose.y, 0.0);  // flying north
}

TEST(Estimator, ClimbShowsAsRisingZ) {
  const test::Flight flight =
      test::renderFlight(test::flightTexture(), test::straightLine(10, 3.0, 2.0, 0.0, 1.02), kN);
  const std::vector<Estimate> estimates = run(flight, flightConfig());
  expectFinite(estimates);
  const double expected_z = (flight.truth.back().altitude - 1.0) * kN;  // about 49 units
  double previous_z = 0.0;
  for (std::size_t k = 1; k < estimates.size(); ++k) {
    EXPECT_GT(estimates[k].pose.z, previous_z) << k;
    previous_z = estimates[k].pose.z;
    EXPECT_LT(estimates[k].step.log_zoom, 0.0) << k;  // content shrinks while climbing
  }
  EXPECT_NEAR(estimates.back().pose.z, expected_z, 0.05 * expected_z);
  // A constant climb rate keeps the zoom energy vectors aligned (PMS ~ 0).
  EXPECT_NEAR(estimates.back().pms12.value, 0.0, 0.3);
}

TEST(Estimator, RescaleIsAsIfTheFlightHadStartedAtThatAltitude) {
  // A climbing flight, twice: from the true altitude, and from 0.7 of it (a rangefinder's first
  // reading of a roof) rescaled by 1/0.7 after 5 frames (its readings' vote). From then on the
  // two are the same flight: the same poses, covariances and later steps.
  const test::Flight flight =
      test::renderFlight(test::flightTexture(), test::straightLine(10, 3.0, 2.0, 0.0, 1.02), kN);
  EstimatorConfig low = flightConfig();
  low.initial_altitude = 0.7 * kN;
  Estimator truth(flightConfig()), rescaled(low);
  for (std::size_t k = 0; k < flight.frames.size(); ++k) {
    const std::optional<Estimate> a = truth.push(flight.frames[k], static_cast<double>(k));
    std::optional<Estimate> b = rescaled.push(flight.frames[k], static_cast<double>(k));
    ASSERT_TRUE(a && b);
    if (k == 4) {
      EXPECT_NEAR(b->pose.x, 0.7 * a->pose.x, 1e-6 * kN);  // before: at 0.7 of the scale
      rescaled.rescale(1.0 / 0.7);
      b->pose = rescaled.pose();
    }
    if (k < 4) continue;
    const Pose4& p = a->pose;
    const Pose4& q = b->pose;
    EXPECT_NEAR(q.x, p.x, 1e-6 * kN) << k;
    EXPECT_NEAR(q.y, p.y, 1e-6 * kN) << k;
    EXPECT_NEAR(q.z, p.z, 1e-6 * kN) << k;
    EXPECT_NEAR(q.yaw, p.yaw, 1e-9) << k;
    EXPECT_NEAR(rescaled.altitude(), truth.altitude(), 1e-6 * kN) << k;
    for (int r = 0; r < 4; ++r) {
      for (int c = 0; c < 4; ++c) {
        EXPECT_NEAR(q.covariance(r, c), p.covariance(r, c), 1e-6 * (std::fabs(p.covariance(r, c)) + 1e-6)) << k;
      }
    }
  }
  EXPECT_GT(truth.pose().z, 10.0);  // it climbed: z was rescaled too
}

TEST(Estimator, YawAndDirectionFollowTheRightHandRule) {
  // Turning counter-clockwise (seen from above) while flying east-north-east.
  const test::Flight flight = test::renderFlight(
      test::flightTexture(), test::straightLine(12, 6.0, 2.0, test::rad(1.0), 1.0), kN);
  const std::vector<Estimate> estimates = run(flight, flightConfig());
  expectFinite(estimates);
  const Pose4& last = estimates.back().pose;
  EXPECT_GT(last.yaw, 0.0);
  EXPECT_NEAR(last.yaw, flight.truth.back().yaw, test::rad(0.5));
  EXPECT_LT(relativeEndError(estimates, flight), 0.015);
  // Content turned clockwise on screen: theta < 0 per pair.
  EXPECT_LT(estimates[3].step.rotation, 0.0);
}

TEST(Estimator, ComparisonModesRunTheSameFlight) {
  const test::Flight flight =
      test::renderFlight(test::flightTexture(), test::straightLine(10, -6.0, 4.0), kN);
  for (EstimatorMode mode : {EstimatorMode::kFmt, EstimatorMode::kEfmt}) {
    const std::vector<Estimate> estimates = run(flight, flightConfig(mode));
    expectFinite(estimates);
    EXPECT_EQ(estimates.back().mode, mode);
    EXPECT_EQ(estimates.back().state, TrackingState::kTracking);
    EXPECT_FALSE(estimates.back().has_registration02);  // consecutive pairs only
    EXPECT_EQ(estimates.back().loop.status, OptimizerStatus::kSkipped);
    EXPECT_LT(relativeEndError(estimates, flight), 0.02) << toString(mode);
    if (mode == EstimatorMode::kFmt) {
      EXPECT_TRUE(estimates.back().registration12.translation_energy.empty());
    } else {
      EXPECT_TRUE(estimates.back().pmt12.valid);
    }
  }
}

// Two depths: roofs nearer the camera move 1.4 times as far. The flight goes from a region of
// sparse roofs (the ground dominates the correlation) into dense roofs (the roofs dominate). The
// classic method's length jumps with the dominant layer; o-eFMT keeps following the ground.
TEST(Estimator, MultiDepthFlightKeepsTheScaleOfTheFirstLayer) {
  const cv::Size size(2048, 2048);
  const cv::Mat1f ground = sim::proceduralTexture(size, 41, sim::TextureStyle::kCells, 40);
  const cv::Mat1f roofs = sim::proceduralTexture(size, 42, sim::TextureStyle::kCells, 40);
  const cv::Mat1f sparse = sim::blockMask(size, 43, 64.0, 0.1);
  const cv::Mat1f dense = sim::blockMask(size, 44, 64.0, 0.95);
  cv::Mat1f mask = sparse.clone();
  const int boundary = 1024 + 100;  // texture column where the dense roofs begin
  dense.colRange(boundary, size.width).copyTo(mask.colRange(boundary, size.width));
  std::vector<cv::Point2d> positions;
  for (int k = 0; k < 24; ++k) positions.emplace_back(7.0 * k, 0.0);
  const test::Flight flight = test::renderTwoLayerFlight(ground, roofs, mask, positions, 1.4, kN);

  const std::vector<Estimate> oefmt = run(flight, flightConfig(EstimatorMode::kOefmt));
  const std::vector<Estimate> fmt = run(flight, flightConfig(EstimatorMode::kFmt));
  expectFinite(oefmt);
  expectFinite(fmt);
  const double oefmt_error = relativeEndError(oefmt, flight);
  const double fmt_error = relativeEndError(fmt, flight);
  EXPECT_LT(oefmt_error, 0.03);
  EXPECT_GT(fmt_error, 3.0 * oefmt_error) << "oefmt " << oefmt_error << ", fmt " << fmt_error;
  // The layer gate noticed the roofs taking over the correlation peak.
  bool gated = false;
  for (const Estimate& e : oefmt) gated |= e.translation_use12 != PairObservations::TranslationUse::kVector;
  EXPECT_TRUE(gated);
  // ... and the diagnostics say which reading then gave the ground's length.
  bool from_other_reading = false;
  for (const Estimate& e : oefmt) {
    from_other_reading |= e.length_source != LengthSource::kPeak && e.length_source != LengthSource::kNone;
  }
  EXPECT_TRUE(from_other_reading);
}

TEST(Estimator, UnregistrableFramesArePredictedThenTrackingResumes) {
  const test::Flight flight =
      test::renderFlight(test::flightTexture(), test::straightLine(12, 5.0, 3.0), kN);
  Estimator estimator(flightConfig());
  const cv::Mat1f black(kN, kN, 0.0f);
  const cv::Mat1f nan_image(kN, kN, std::numeric_limits<float>::quiet_NaN());
  std::vector<Estimate> estimates;
  for (std::size_t k = 0; k < flight.frames.size(); ++k) {
    const cv::Mat1f& frame = (k == 5) ? black : (k == 6 ? nan_image : flight.frames[k]);
    std::optional<Estimate> e = estimator.push(frame, static_cast<double>(k));
    ASSERT_TRUE(e.has_value());
    estimates.push_back(*e);
  }
  expectFinite(estimates);
  EXPECT_EQ(estimates[5].state, TrackingState::kPredicted);
  EXPECT_EQ(estimates[6].state, TrackingState::kPredicted);
  EXPECT_EQ(estimates[5].length_source, LengthSource::kNone);
  EXPECT_TRUE(estimates[5].degraded);
  EXPECT_GT(estimates[6].pose.covariance(0, 0), 10.0 * estimates[4].pose.covariance(0, 0));
  EXPECT_EQ(estimates[7].state, TrackingState::kTracking);
  EXPECT_EQ(estimates[7].frame_gap, 3);  // frame 4 -> frame 7
  EXPECT_EQ(estimates.back().state, TrackingState::kTracking);
  // The predictions were replaced by the real motion once it was measured.
  EXPECT_LT(relativeEndError(estimates, flight), 0.015);
}

// The view changes to another scene (another texture under the same flight): the first frame of
// it matches nothing before it and is predicted; the next one matches nothing two intervals back
// either, but its predecessor one interval back, from whose predicted pose tracking resumes at
// once instead of after a restart.
TEST(Estimator, TheFrameAfterAFailedOneRegistersAgainstIt) {
  const std::vector<test::CameraState> track = test::straightLine(11, 5.0, 3.0);
  const test::Flight first = test::renderFlight(test::flightTexture(), track, kN);
  const cv::Mat1f other_scene =
      sim::proceduralTexture(test::flightTexture().size(), 57, sim::TextureStyle::kCells, 40.0);
  const test::Flight second = test::renderFlight(other_scene, track, kN);
  Estimator estimator(flightConfig());
  std::vector<Estimate> estimates;
  for (std::size_t k = 0; k < track.size(); ++k) {
    const cv::Mat1f& frame = k < 6 ? first.frames[k] : second.frames[k];
    std::optional<Estimate> e = estimator.push(frame, static_cast<double>(k));
    ASSERT_TRUE(e.has_value());
    estimates.push_back(*e);
  }
  expectFinite(estimates);
  EXPECT_EQ(estimates[6].state, TrackingState::kPredicted);
  for (std::size_t k = 7; k < estimates.size(); ++k) {
    EXPECT_EQ(estimates[k].state, TrackingState::kTracking) << "frame " << k;
    EXPECT_EQ(estimates[k].frame_gap, 1) << "frame " << k;
  }
  // The steps after the change are measured: each within 3 % of the true one.
  for (std::size_t k = 7; k < estimates.size(); ++k) {
    const double dx = estimates[k].pose.x - estimates[k - 1].pose.x;
    const double dy = estimates[k].pose.y - estimates[k - 1].pose.y;
    const double tx = track[k].east - track[k - 1].east, ty = track[k].north - track[k - 1].north;
    EXPECT_LT(std::hypot(dx - tx, dy - ty), 0.03 * std::hypot(tx, ty)) << "frame " << k;
  }
  EXPECT_LT(relativeEndError(estimates, first), 0.02);
}

TEST(Estimator, LongFailuresRestartTheWindow) {
  const test::Flight flight =
      test::renderFlight(test::flightTexture(), test::straightLine(6, 4.0, 0.0), kN);
  EstimatorConfig config = flightConfig();
  config.tracking.max_failed_frames = 2;
  Estimator estimator(config);
  const cv::Mat1f grey(kN, kN, 0.5f);
  std::vector<TrackingState> states;
  for (int k = 0; k < 3; ++k) states.push_back(estimator.push(flight.frames[k], k)->state);
  std::vector<double> xs;
  for (int k = 3; k < 6; ++k) {
    const std::optional<Estimate> e = estimator.push(grey, k);
    states.push_back(e->state);
    xs.push_back(e->pose.x);
  }
  // Failed frames are predicted, the one that restarts the window too (the vehicle kept
  // moving); a textureless frame cannot anchor the restart: the pose is held from then until a
  // textured one comes.
  EXPECT_EQ(states[3], TrackingState::kPredicted);
  EXPECT_EQ(states[4], TrackingState::kPredicted);
  EXPECT_EQ(states[5], TrackingState::kPredicted);
  EXPECT_GT(std::fabs(xs[2] - xs[1]), 0.5 * std::fabs(xs[1] - xs[0])) << "the restarting frame moved on";
  const std::optional<Estimate> anchor = estimator.push(flight.frames[3], 6.0);
  EXPECT_EQ(anchor->state, TrackingState::kHeld);  // becomes the new anchor
  const std::optional<Estimate> resumed = estimator.push(flight.frames[4], 7.0);
  EXPECT_EQ(resumed->state, TrackingState::kTracking);
  EXPECT_TRUE(resumed->pose.finite());
}

TEST(Estimator, TheFrameThatRestartsTheWindowIsPredicted) {
  const test::Flight flight =
      test::renderFlight(test::flightTexture(), test::straightLine(3, 4.0, 0.0), kN);
  EstimatorConfig config = flightConfig();
  config.tracking.max_failed_frames = 2;
  Estimator estimator(config);
  double x = 0.0, previous_x = 0.0;
  for (int k = 0; k < 3; ++k) {
    previous_x = x;
    x = estimator.push(flight.frames[k], k)->pose.x;
  }
  const double step = x - previous_x;
  ASSERT_GT(std::fabs(step), 1.0);
  // Textured frames that match nothing before them (a camera swung away): two predicted, then
  // the restart, whose pose is predicted too.
  cv::RNG rng(7);
  for (int k = 3; k < 6; ++k) {
    cv::Mat1f unrelated(kN, kN);
    rng.fill(unrelated, cv::RNG::UNIFORM, 0.0f, 1.0f);
    cv::GaussianBlur(unrelated, unrelated, cv::Size(0, 0), 3.0);
    const std::optional<Estimate> e = estimator.push(unrelated, k);
    ASSERT_TRUE(e.has_value());
    EXPECT_EQ(e->state, k < 5 ? TrackingState::kPredicted : TrackingState::kRestarted) << "frame " << k;
    EXPECT_NEAR(e->pose.x - x, step, 0.05 * std::fabs(step)) << "frame " << k;
    x = e->pose.x;
  }
}

// Tracking is lost over a ground scene (unrelated views, a camera swung away) and restarts over
// another one that lies at 80 % of the depth (roofs): at the same speed its content moves 1.25
// times as far per frame. The restart's first pair has no scale of its own; the vehicle kept its
// speed over the few frames that failed, so the steps after the restart keep the ground's metres
// per frame instead of 1.25 times them.
TEST(Estimator, ARestartOnAnotherDepthLayerKeepsTheSpeed) {
  constexpr int kFrames = 18;
  const test::Flight ground = test::renderFlight(test::flightTexture(), test::straightLine(kFrames, 5.0, 0.0), kN);
  const cv::Mat1f roof_texture =
      sim::proceduralTexture(test::flightTexture().size(), 57, sim::TextureStyle::kCells, 40.0);
  const test::Flight roofs = test::renderFlight(roof_texture, test::straightLine(kFrames, 6.25, 0.0), kN);
  EstimatorConfig config = flightConfig();
  config.tracking.max_failed_frames = 2;
  Estimator estimator(config);
  cv::RNG rng(7);
  std::vector<Estimate> estimates;
  for (int k = 0; k < kFrames; ++k) {
    cv::Mat1f frame;
    if (k < 6) {
      frame = ground.frames[k];
    } else if (k < 9) {
      frame.create(kN, kN);
      rng.fill(frame, cv::RNG::UNIFORM, 0.0f, 1.0f);
      cv::GaussianBlur(frame, frame, cv::Size(0, 0), 3.0);
    } else {
      frame = roofs.frames[k];
    }
    const std::optional<Estimate> e = estimator.push(frame, static_cast<double>(k));
    ASSERT_TRUE(e.has_value());
    estimates.push_back(*e);
  }
  ASSERT_EQ(estimates[8].state, TrackingState::kRestarted);
  // The roofs' steps within 5 % of the ground's 5 px (the roof scene's own registration reads
  // its 6.25 px within 2-3 %), where 25 % further without the restart's speed.
  int tracked = 0;
  for (int k = 10; k < kFrames; ++k) {
    if (estimates[k].state != TrackingState::kTracking || estimates[k - 1].state != TrackingState::kTracking) continue;
    ++tracked;
    const double step = std::hypot(estimates[k].pose.x - estimates[k - 1].pose.x,
                                   estimates[k].pose.y - estimates[k - 1].pose.y);
    EXPECT_NEAR(step, 5.0, 0.25) << "frame " << k;
  }
  EXPECT_GE(tracked, 4);
}

TEST(Estimator, ResetStampsAndBadInput) {
  const test::Flight flight =
      test::renderFlight(test::flightTexture(), test::straightLine(3, 4.0, 0.0), kN);
  Estimator estimator(flightConfig());
  EXPECT_TRUE(estimator.push(flight.frames[0], 1.0).has_value());
  EXPECT_TRUE(estimator.push(flight.frames[1], 2.0).has_value());
  EXPECT_GT(std::fabs(estimator.pose().x), 1.0);
  // Frames from the past or without a valid stamp are ignored.
  EXPECT_FALSE(estimator.push(flight.frames[2], 1.5).has_value());
  EXPECT_FALSE(estimator.push(flight.frames[2], std::nan("")).has_value());
  EXPECT_EQ(estimator.frameCount(), 2u);
  EXPECT_THROW(estimator.push(cv::Mat(), 3.0), InputError);
  estimator.reset();
  const std::optional<Estimate> first = estimator.push(flight.frames[2], 0.5);
  ASSERT_TRUE(first.has_value());
  EXPECT_EQ(first->frame_index, 0u);
  EXPECT_EQ(first->state, TrackingState::kStarted);
  EXPECT_DOUBLE_EQ(first->pose.x, 0.0);
  // Prepared images take the same path.
  const std::optional<Estimate> second =
      estimator.push(prepareImage(flight.frames[1], kN), 1.0);
  ASSERT_TRUE(second.has_value());
  EXPECT_EQ(second->state, TrackingState::kTracking);
  EXPECT_LT(second->pose.x, -1.0);  // frame 1 is west of frame 2
}

// oefmt_offline analyses frames on its reader thread with a SpectraBuilder sharing the
// estimator's context: the poses must be those of pushing the images themselves.
TEST(Estimator, FramesAnalysedAheadGiveTheSamePoses) {
  const test::Flight flight =
      test::renderFlight(test::flightTexture(), test::straightLine(6, 5.0, -2.0, 0.01, 1.01), kN);
  const EstimatorConfig config = flightConfig();
  const std::vector<Estimate> direct = run(flight, config);
  const auto context = std::make_shared<const SpectralContext>(config.registration);
  Estimator estimator(config, context);
  EXPECT_EQ(estimator.spectralContext(), context);
  SpectraBuilder builder(context);
  ASSERT_EQ(direct.size(), flight.frames.size());
  for (std::size_t k = 0; k < flight.frames.size(); ++k) {
    const std::optional<Estimate> e = estimator.push(builder.build(flight.frames[k]), static_cast<double>(k));
    ASSERT_TRUE(e.has_value()) << k;
    EXPECT_EQ(e->state, direct[k].state) << k;
    EXPECT_DOUBLE_EQ(e->pose.x, direct[k].pose.x) << k;
    EXPECT_DOUBLE_EQ(e->pose.y, direct[k].pose.y) << k;
    EXPECT_DOUBLE_EQ(e->pose.z, direct[k].pose.z) << k;
    EXPECT_DOUBLE_EQ(e->pose.yaw, direct[k].pose.yaw) << k;
  }
  EXPECT_GT(std::fabs(estimator.pose().x), 10.0);
  // Out-of-order stamps are ignored as for images; empty or other-size spectra are refused.
  EXPECT_FALSE(estimator.push(builder.build(flight.frames[0]), 1.0).has_value());
  EXPECT_THROW(estimator.push(FrameSpectra{}, 10.0), InputError);
  RegistrationConfig half = config.registration;
  half.size = kN / 2;
  SpectraBuilder other_size(std::make_shared<const SpectralContext>(half));
  EXPECT_THROW(estimator.push(other_size.build(flight.frames[0]), 10.0), InputError);
  // A context made for other registration parameters is refused.
  RegistrationConfig other = config.registration;
  other.taper_fraction = 0.2;
  EXPECT_THROW(Estimator(config, std::make_shared<const SpectralContext>(other)), InputError);
  EXPECT_THROW(Estimator(config, nullptr), InputError);
}

TEST(Estimator, InvalidConfigurationIsRejected) {
  EstimatorConfig config = flightConfig();
  config.initial_altitude = -1.0;
  EXPECT_THROW(Estimator{config}, InputError);
  config = flightConfig();
  config.registration.size = 100 + 1;
  EXPECT_THROW(Estimator{config}, InputError);
}

}  // namespace
}  // namespace oefmt
