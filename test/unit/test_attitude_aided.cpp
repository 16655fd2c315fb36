// SPDX-License-Identifier: GPL-3.0-or-later
// Attitude-aided registration: the camera's tilt read from its orientation, interpolation of an
// IMU's orientations between samples, and the claim it rests on: a pure roll or pitch between
// two frames over flat ground, once both frames are turned into the level view, registers as no
// translation (while the raw frames register as tens of pixels of it).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "oefmt/estimation/attitude.h"
#include "oefmt/estimation/estimator.h"
#include "oefmt/io/nadir_view.h"
#include "oefmt/registration/registration.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/renderer.h"
#include "support/fixtures.h"
#include "support/flight_fixtures.h"

namespace oefmt {
namespace {

constexpr double kDeg = M_PI / 180.0;

Eigen::Matrix3d opticalOf(const Eigen::Quaterniond& body) { return body.toRotationMatrix() * downLookingMount(); }

TEST(Attitude, TiltComesBackFromTheOrientationWhateverTheYaw) {
  for (const double yaw : {0.0, 1.0, -2.5, 3.0}) {
    for (const CameraTilt tilt : {CameraTilt{0.0, 0.0}, CameraTilt{0.1, -0.2}, CameraTilt{-0.3, 0.05}}) {
      const CameraTilt back = cameraTilt(opticalOf(cameraBodyOrientation(yaw, tilt)));
      EXPECT_NEAR(back.roll, tilt.roll, 1e-12);
      EXPECT_NEAR(back.pitch, tilt.pitch, 1e-12);
    }
  }
  // Level: the nadir rotation is the identity.
  EXPECT_TRUE(nadirFromOptical(CameraTilt{}).isApprox(Eigen::Matrix3d::Identity(), 1e-15));
  // The nadir rotation takes the tilted optical axis to the level one: straight down.
  const double yaw = 0.7;
  const CameraTilt tilt{0.2, -0.1};
  const Eigen::Matrix3d optical = opticalOf(cameraBodyOrientation(yaw, tilt));
  const Eigen::Matrix3d virtual_optical = optical * nadirFromOptical(tilt).transpose();
  EXPECT_TRUE(virtual_optical.col(2).isApprox(Eigen::Vector3d(0.0, 0.0, -1.0), 1e-12));
}

TEST(Attitude, TiltAngleIsTheViewsAngleFromStraightDown) {
  EXPECT_NEAR(tiltAngle(CameraTilt{0.2, 0.0}), 0.2, 1e-12);
  EXPECT_NEAR(tiltAngle(CameraTilt{0.0, -0.3}), 0.3, 1e-12);
  // Roll then pitch: the view's z is (cos p cos r) down.
  EXPECT_NEAR(tiltAngle(CameraTilt{0.1, 0.2}), std::acos(std::cos(0.1) * std::cos(0.2)), 1e-12);
  EXPECT_EQ(tiltAngle(CameraTilt{}), 0.0);
  // Nothing added without a tilt to fear, or with a meaningless one.
  std::array<double, 36> covariance{};
  addUnknownTilt(covariance, 20.0, 0.0);
  addUnknownTilt(covariance, std::nan(""), 0.1);
  for (const double c : covariance) EXPECT_EQ(c, 0.0);
}

TEST(Attitude, HistoryInterpolatesBetweenSamplesAndNotAcrossGaps) {
  AttitudeHistory history(0.1);
  const Eigen::Quaterniond a(Eigen::AngleAxisd(0.0, Eigen::Vector3d::UnitX()));
  const Eigen::Quaterniond b(Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitX()));
  EXPECT_TRUE(history.add(1.0, a));
  EXPECT_TRUE(history.add(1.05, b));
  EXPECT_FALSE(history.add(1.05, a));  // not after the newest
  EXPECT_TRUE(history.add(1.5, a));    // after a gap
  const auto middle = history.at(1.025);
  ASSERT_TRUE(middle.has_value());
  EXPECT_NEAR(Eigen::AngleAxisd(*middle).angle(), 0.05, 1e-12);
  EXPECT_TRUE(history.at(1.05).has_value());
  EXPECT_FALSE(history.at(0.99).has_value());  // before the first
  EXPECT_FALSE(history.at(1.3).has_value());   // in the gap
  EXPECT_FALSE(history.at(1.6).has_value());   // after the newest
  history.forgetBefore(1.5);
  EXPECT_TRUE(history.at(1.5).has_value());
  // A camera's tilt from the body's orientation and the camera's mount: a mount turned 10 degrees
  // about the body's y adds 10 degrees of pitch.
  AttitudeHistory level;
  level.add(0.0, Eigen::Quaterniond::Identity());
  level.add(0.05, Eigen::Quaterniond::Identity());
  EXPECT_NEAR(cameraTiltAt(level, 0.02)->pitch, 0.0, 1e-12);
  const Eigen::Matrix3d mount = Eigen::AngleAxisd(0.1745, Eigen::Vector3d::UnitY()).toRotationMatrix() * downLookingMount();
  EXPECT_NEAR(cameraTiltAt(level, 0.02, mount)->pitch, 0.1745, 1e-9);
  EXPECT_FALSE(cameraTiltAt(level, 0.2).has_value());
}

// A kNadirN-pixel square camera of focal length 100 px and its level view at the same size.
constexpr int kNadirN = 128;

NadirView squareNadirView() {
  CameraParameters camera;
  camera.intrinsics = Intrinsics{100.0, 100.0, (kNadirN - 1) / 2.0, (kNadirN - 1) / 2.0, kNadirN, kNadirN};
  return NadirView(camera, cv::Size(kNadirN, kNadirN), camera.intrinsics.fx, kNadirN);
}

// The rows of a level view that hold one value across: the fill of what the camera did not see.
std::vector<int> uniformRows(const cv::Mat1f& view) {
  std::vector<int> rows;
  for (int y = 0; y < view.rows; ++y) {
    double low = 0.0, high = 0.0;
    cv::minMaxLoc(view.row(y), &low, &high);
    if (high - low < 1e-3) rows.push_back(y);
  }
  return rows;
}

cv::Mat1f whiteNoiseFrame() {
  cv::Mat1f frame(kNadirN, kNadirN);
  cv::randu(frame, 0.0f, 255.0f);
  return frame;
}

TEST(NadirView, ALevelFrameComesOutAsItIsAndOnlyWhatWasNotSeenFades) {
  const cv::Mat1f frame = whiteNoiseFrame();
  const NadirView nadir = squareNadirView();
  // Level: every pixel, the edges' too, is the frame's own (the bicubic kernel's reach beyond
  // the last row is no reason to fade it).
  const cv::Mat1f level = nadir.apply(frame, nadirFromOptical(CameraTilt{}));
  EXPECT_LT(cv::norm(level, frame, cv::NORM_INF), 1e-3);
  // Rolled: the view's far side was not seen and holds the seen part's mean; the side the
  // camera leans toward keeps the texture as seen from there, unfaded beyond the ramp.
  const cv::Mat1f rolled = nadir.apply(frame, nadirFromOptical(CameraTilt{10.0 * kDeg, 0.0}));
  const std::vector<int> unseen_rows = uniformRows(rolled);
  EXPECT_GT(unseen_rows.size(), 5u);
  for (const int y : unseen_rows) EXPECT_NEAR(rolled(y, 0), 127.5, 5.0) << "row " << y;
  int textured_rows = 0;
  for (int y = 0; y < kNadirN; ++y) {
    double low = 0.0, high = 0.0;
    cv::minMaxLoc(rolled.row(y), &low, &high);
    if (high - low > 100.0) ++textured_rows;
  }
  EXPECT_GT(textured_rows, kNadirN / 2);
  // A float frame's missing pixels are not seen either: faded like the rest, never passed on.
  cv::Mat1f holed = frame.clone();
  holed(kNadirN / 2, kNadirN / 2) = std::numeric_limits<float>::quiet_NaN();
  holed(3, 7) = std::numeric_limits<float>::infinity();
  for (const CameraTilt tilt : {CameraTilt{}, CameraTilt{10.0 * kDeg, 0.0}}) {
    EXPECT_TRUE(cv::checkRange(nadir.apply(holed, nadirFromOptical(tilt)))) << tilt.roll;
  }
  // Level, beyond the fade around the holes the frame is its own.
  const cv::Rect far_from_holes(kNadirN - 40, kNadirN - 40, 40, 40);
  EXPECT_LT(cv::norm(nadir.apply(holed, nadirFromOptical(CameraTilt{}))(far_from_holes), frame(far_from_holes),
                     cv::NORM_INF),
            1e-3);
}

TEST(NadirView, TheFadeGrowsFromNothingAsTheCameraTiltsAwayFromLevel) {
  // Views of nearly the same attitude are nearly the same, also where the first row of the view
  // goes unseen: that row takes the mean, and no band along the edge fades with it (a folder's
  // attitudes, printed to nine digits, and a bag's doubles then give the same trajectory).
  const cv::Mat1f frame = whiteNoiseFrame();
  const NadirView nadir = squareNadirView();
  const auto view = [&](double roll) { return nadir.apply(frame, nadirFromOptical(CameraTilt{roll, 0.0})); };
  const auto anyRowUnseen = [](const cv::Mat1f& v) { return !uniformRows(v).empty(); };
  // The roll at which a row of the view first goes unseen.
  double seen = 0.0, unseen = 2.0 * kDeg;
  ASSERT_FALSE(anyRowUnseen(view(seen)));
  ASSERT_TRUE(anyRowUnseen(view(unseen)));
  while (unseen - seen > 1e-10) {
    const double middle = 0.5 * (seen + unseen);
    (anyRowUnseen(view(middle)) ? unseen : seen) = middle;
  }
  cv::Mat1f difference;
  cv::absdiff(view(seen), view(unseen), difference);
  EXPECT_LE(cv::countNonZero(difference > 1.0f), 2 * kNadirN) << "more than the row that went unseen changed";
  // Further on, the ramp widens with what was not seen, up to its full width.
  const cv::Mat1f tilted = view(6.0 * kDeg);
  int faded_rows = 0;
  for (int y = 0; y < kNadirN; ++y) {
    cv::Scalar mean, spread;
    cv::meanStdDev(tilted.row(y), mean, spread);
    if (spread[0] > 1e-3 && spread[0] < 0.8 * 255.0 / std::sqrt(12.0)) ++faded_rows;
  }
  EXPECT_GE(faded_rows, 3);
}

TEST(NadirView, PrepareMarksAsSeenOnlyWhatTheCameraSawUnfaded) {
  const cv::Mat1f frame = whiteNoiseFrame();
  const NadirView nadir = squareNadirView();
  // Level: all of it was seen, and the view is apply()'s.
  const PreparedImage level = nadir.prepare(frame, nadirFromOptical(CameraTilt{}));
  EXPECT_TRUE(level.seen.empty());
  EXPECT_LT(cv::norm(level.grey, nadir.apply(frame, nadirFromOptical(CameraTilt{})), cv::NORM_INF), 1e-6);
  // Rolled: the filled rows and the fade into them are not seen; the rest is.
  const Eigen::Matrix3d rolled = nadirFromOptical(CameraTilt{10.0 * kDeg, 0.0});
  const PreparedImage view = nadir.prepare(frame, rolled);
  EXPECT_LT(cv::norm(view.grey, nadir.apply(frame, rolled), cv::NORM_INF), 1e-6);
  ASSERT_EQ(view.seen.size(), view.grey.size());
  const std::vector<int> fill_rows = uniformRows(view.grey);
  ASSERT_GT(fill_rows.size(), 5u);
  // The ramp is as wide as the fill is deep, up to a sixteenth of the view (8 rows here): the
  // fill's rows and the four next to it are not the camera's own.
  for (int y = 0; y < kNadirN; ++y) {
    int rows_from_fill = kNadirN;
    for (const int f : fill_rows) rows_from_fill = std::min(rows_from_fill, std::abs(y - f));
    const int seen = cv::countNonZero(view.seen.row(y));
    if (rows_from_fill <= 4) {
      EXPECT_EQ(seen, 0) << "row " << y;
    }
  }
  // The camera saw most of the view: ten degrees of roll leave a sixth of it unseen here.
  EXPECT_GT(cv::countNonZero(view.seen), kNadirN * kNadirN / 2) << cv::countNonZero(view.seen);
}

// The pairs' ln(zoom) errors along a tilting multirotor's flight at one altitude over the
// simulator's default scene (its truth: 0 for every layer), each frame levelled with its exact
// attitude, registered with and without the masks of what the camera saw.
struct LevelledZooms {
  double rms_with_masks = 0.0;
  double rms_without = 0.0;
  int pairs = 0;
};

LevelledZooms levelledPairZooms() {
  constexpr int kN = 512;
  sim::FlightOptions options;
  options.tilt.follow_acceleration = true;
  options.tilt.wobble = 8.0 * kDeg;
  options.tilt.wobble_frequency = 1.0;
  options.seed = 35;
  const sim::FlightPlan plan = test::plannedFlight(options, 25);
  const std::vector<cv::Mat1b> frames = test::renderPlan(plan);
  const NadirView nadir(plan.camera, frames[0].size(), plan.camera.intrinsics.fx, kN);
  Registrar registrar(test::sharedContext(kN));
  LevelledZooms zooms;
  for (const bool masked : {true, false}) {
    std::optional<FrameSpectra> older;
    double squares = 0.0;
    int pairs = 0;
    for (std::size_t k = 0; k < frames.size(); ++k) {
      const sim::FlightPose& pose = plan.poses[k];
      PreparedImage view = nadir.prepare(frames[k], nadirFromOptical(CameraTilt{pose.roll, pose.pitch}));
      if (!masked) view.seen.release();
      FrameSpectra newer = registrar.analyse(view);
      if (older) {
        const PairRegistration r = registrar.registerPair(*older, newer);
        if (r.status == RegistrationStatus::kOk && r.zoom_refined) {
          squares += std::pow(std::log(r.zoom), 2);
          ++pairs;
        }
      }
      older = std::move(newer);
    }
    (masked ? zooms.rms_with_masks : zooms.rms_without) = std::sqrt(squares / std::max(pairs, 1));
    if (masked) zooms.pairs = pairs;
  }
  return zooms;
}

TEST(AttitudeAidedRegistration, WhatTheCameraDidNotSeeDoesNotPullTheZoom) {
  // A levelled view fills in what the camera did not see and fades its texture into the fill
  // (the spectra need no hard edge there). Fill and fade stay where the tilt put them whatever
  // the scene did: read as texture by the zoom refinement they pull its fit, and the pairs'
  // zoom, which carries the altitude, errs (about three times as much on this flight).
  const LevelledZooms zooms = levelledPairZooms();
  ASSERT_GE(zooms.pairs, 20);
  EXPECT_LT(zooms.rms_with_masks, 0.5 * zooms.rms_without)
      << "ln(zoom) rms " << zooms.rms_with_masks << " with the masks, " << zooms.rms_without << " without";
}

TEST(AttitudeAidedRegistration, PureRollOrPitchRegistersAsNoTranslation) {
  constexpr int kN = 256;
  sim::FlightOptions options;
  options.width = options.height = kN;
  options.flat = true;
  options.track.frames = 2;
  options.track.length = 1.0;
  options.track.altitude = 20.0;
  options.seed = 3;
  const sim::FlightPlan plan = sim::planFlight(options);
  const auto scene = std::make_shared<const sim::Scene>(plan.scene);
  const sim::Renderer renderer(scene, plan.camera, 2);
  const NadirView nadir(plan.camera, cv::Size(kN, kN), plan.camera.intrinsics.fx, kN);
  Registrar registrar(test::sharedContext(kN));

  sim::FlightPose level = plan.poses[0];
  const cv::Mat1f level_view = nadir.apply(renderer.render(level).image, nadirFromOptical(CameraTilt{}));
  const FrameSpectra reference = registrar.analyse(level_view);
  for (const CameraTilt tilt : {CameraTilt{6.0 * kDeg, 0.0}, CameraTilt{0.0, -5.0 * kDeg}, CameraTilt{4.0 * kDeg, 3.0 * kDeg}}) {
    sim::FlightPose tilted = level;
    tilted.roll = tilt.roll;
    tilted.pitch = tilt.pitch;
    const cv::Mat1f raw = renderer.render(tilted).image;
    const PairRegistration unaided = registrar.registerPair(reference, registrar.analyse(raw));
    const PairRegistration aided =
        registrar.registerPair(reference, registrar.analyse(nadir.apply(raw, nadirFromOptical(tilt))));
    // Unaided, the tilt is seen as a shift of about f tan(tilt): 19-23 px here.
    const double seen_as_shift = plan.camera.intrinsics.fx * std::tan(std::hypot(tilt.roll, tilt.pitch));
    EXPECT_NEAR(cv::norm(unaided.translation), seen_as_shift, 0.15 * seen_as_shift) << tilt.roll << " " << tilt.pitch;
    // A frame the node must take as level (its IMU went quiet) carries that shift in its
    // position's covariance: per axis, one sigma of a tilt as large as this one reaches it.
    std::array<double, 36> covariance{};
    addUnknownTilt(covariance, options.track.altitude, tiltAngle(tilt));
    const double metres_per_px = options.track.altitude / plan.camera.intrinsics.fx;
    EXPECT_NEAR(std::hypot(unaided.translation.x, unaided.translation.y) * metres_per_px,
                std::sqrt(covariance[0]), 0.15 * std::sqrt(covariance[0]));
    EXPECT_LE(std::fabs(unaided.translation.x) * metres_per_px, 1.15 * std::sqrt(covariance[0]));
    EXPECT_LE(std::fabs(unaided.translation.y) * metres_per_px, 1.15 * std::sqrt(covariance[7]));
    EXPECT_DOUBLE_EQ(covariance[3 * 6 + 3], tiltAngle(tilt) * tiltAngle(tilt));
    EXPECT_DOUBLE_EQ(covariance[4 * 6 + 4], tiltAngle(tilt) * tiltAngle(tilt));
    EXPECT_DOUBLE_EQ(covariance[2 * 6 + 2], 0.0);  // the altitude is not what a tilt changes
    EXPECT_LT(cv::norm(aided.translation), 0.5) << tilt.roll << " " << tilt.pitch;
    EXPECT_NEAR(aided.rotation, 0.0, 0.2 * kDeg);
    EXPECT_NEAR(aided.zoom, 1.0, 0.003);
  }
}

TEST(Attitude, TurnHistoryIntegratesTheYawRateNotTheVerticalRate) {
  // A body pitched 10 degrees that rolls at 0.5 rad/s keeps its yaw: about the world's vertical it
  // turns (by -0.5 sin 10 deg per second), about its yaw it does not. Then it yaws at 0.3 rad/s.
  TurnHistory turns(0.1);
  for (int k = 0; k <= 200; ++k) {
    const double t = 0.005 * k;
    const double roll = 0.5 * t;
    const Eigen::Quaterniond body(Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()) *
                                  Eigen::AngleAxisd(10.0 * kDeg, Eigen::Vector3d::UnitY()) *
                                  Eigen::AngleAxisd(roll, Eigen::Vector3d::UnitX()));
    // Body rates of a roll rate alone: p = roll rate.
    ASSERT_TRUE(turns.add(t, body, Eigen::Vector3d(0.5, 0.0, 0.0)));
  }
  ASSERT_TRUE(turns.turn(0.1, 0.9).has_value());
  EXPECT_NEAR(*turns.turn(0.1, 0.9), 0.0, 1e-9);
  TurnHistory yawing(0.1);
  for (int k = 0; k <= 100; ++k) {
    const double t = 0.01 * k;
    const Eigen::Quaterniond body(Eigen::AngleAxisd(0.3 * t, Eigen::Vector3d::UnitZ()));
    yawing.add(t, body, Eigen::Vector3d(0.0, 0.0, 0.3));
  }
  EXPECT_NEAR(*yawing.turn(0.205, 0.705), 0.15, 1e-9);  // ends between samples
  // The same yaw through an IMU mounted upside down and turned a quarter: its own orientation and
  // rates, and its mount, give the body's turn.
  const Eigen::Matrix3d body_from_imu = (Eigen::AngleAxisd(M_PI / 2.0, Eigen::Vector3d::UnitZ()) *
                                         Eigen::AngleAxisd(M_PI, Eigen::Vector3d::UnitX()))
                                            .toRotationMatrix();
  TurnHistory mounted(0.1, body_from_imu.transpose());
  for (int k = 0; k <= 100; ++k) {
    const double t = 0.01 * k;
    const Eigen::Quaterniond body(Eigen::AngleAxisd(0.3 * t, Eigen::Vector3d::UnitZ()) *
                                  Eigen::AngleAxisd(0.1, Eigen::Vector3d::UnitY()));
    mounted.add(t, body * Eigen::Quaterniond(body_from_imu),
                body_from_imu.transpose() * (body.conjugate() * Eigen::Vector3d(0.0, 0.0, 0.3)));
  }
  EXPECT_NEAR(*mounted.turn(0.205, 0.705), 0.15, 1e-9);
  EXPECT_FALSE(yawing.turn(0.5, 1.2).has_value());       // beyond the samples
  EXPECT_FALSE(yawing.turn(-0.1, 0.5).has_value());
  TurnHistory gap(0.1);
  gap.add(0.0, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero());
  gap.add(0.5, Eigen::Quaterniond::Identity(), Eigen::Vector3d::Zero());
  EXPECT_FALSE(gap.turn(0.1, 0.2).has_value());  // nothing is known inside a gap
}

// A straight flight over flat ground whose camera yaws kTurn between frames kTurnFrame - 1 and
// kTurnFrame (125 deg/s at its 5 frames per second), rendered at kN, and the estimator's
// configuration for it.
constexpr int kN = 256;
constexpr int kTurnFrame = 8;
constexpr double kTurn = 25.0 * kDeg;
constexpr double kFrameInterval = 0.2;  // [s]

struct SuddenYawFlight {
  sim::FlightPlan plan;
  std::vector<cv::Mat1f> frames;
  EstimatorConfig config;
};

SuddenYawFlight suddenYawFlight() {
  SuddenYawFlight flight;
  sim::FlightOptions options;
  options.width = options.height = kN;
  options.flat = true;
  options.track.shape = sim::TrackShape::kLine;
  options.track.frames = 12;
  options.track.length = 12.0;
  options.track.altitude = 12.0;
  options.seed = 4;
  flight.plan = sim::planFlight(options);
  std::vector<sim::FlightPose>& poses = flight.plan.poses;
  for (int k = kTurnFrame; k < static_cast<int>(poses.size()); ++k) poses[k].yaw += kTurn;
  const auto scene = std::make_shared<const sim::Scene>(flight.plan.scene);
  const sim::Renderer renderer(scene, flight.plan.camera, 2);
  for (const sim::FlightPose& pose : poses) flight.frames.push_back(renderer.render(pose).image);
  flight.config.registration.size = kN;
  flight.config.registration.fft_planning = FftPlanning::kEstimate;
  flight.config.working_fx = flight.plan.camera.intrinsics.fx;
  return flight;
}

TEST(AttitudeAidedRegistration, AGyrosTurnLetsASuddenYawRegister) {
  // A vehicle flies straight, then yaws 25 degrees between two frames (125 deg/s). The motion so
  // far predicts no turn and searches the rotation near it: the turn is refused as implausible.
  // With the gyro's turn the rotation is searched where it is, and the frame registers.
  const SuddenYawFlight flight = suddenYawFlight();
  const sim::FlightPlan& plan = flight.plan;
  const std::vector<cv::Mat1f>& frames = flight.frames;

  const auto fly = [&](bool gyro) {
    Estimator estimator(flight.config);
    std::vector<Estimate> estimates;
    for (std::size_t k = 0; k < frames.size(); ++k) {
      if (gyro && k > 0) {
        // A gyro whose turn is 1 degree short at the sudden yaw.
        const double turn = plan.poses[k].yaw - plan.poses[k - 1].yaw;
        estimator.setTurn(static_cast<int>(k) == kTurnFrame ? turn - 1.0 * kDeg : turn,
                          kGyroRateError * kFrameInterval);
      }
      const std::optional<Estimate> e = estimator.push(frames[k], kFrameInterval * static_cast<double>(k));
      EXPECT_TRUE(e.has_value());
      if (e) estimates.push_back(*e);
    }
    return estimates;
  };
  const std::vector<Estimate> without = fly(false);
  const std::vector<Estimate> with = fly(true);
  ASSERT_EQ(without.size(), frames.size());
  ASSERT_EQ(with.size(), frames.size());
  const auto yawStep = [](const std::vector<Estimate>& e, int k) {
    return std::remainder(e[k].pose.yaw - e[k - 1].pose.yaw, 2.0 * M_PI);
  };
  // Straight flight before: both track it.
  for (int k = 1; k < kTurnFrame; ++k) {
    EXPECT_EQ(without[k].state, TrackingState::kTracking) << k;
    EXPECT_EQ(with[k].state, TrackingState::kTracking) << k;
  }
  // The turn: the motion model alone does not take it; with the gyro it is measured.
  EXPECT_TRUE(without[kTurnFrame].state != TrackingState::kTracking ||
              std::fabs(std::fabs(yawStep(without, kTurnFrame)) - kTurn) > 2.0 * kDeg)
      << "without the gyro: " << toString(without[kTurnFrame].state) << ", yaw step "
      << yawStep(without, kTurnFrame) / kDeg << " deg";
  EXPECT_EQ(with[kTurnFrame].state, TrackingState::kTracking);
  EXPECT_NEAR(std::fabs(yawStep(with, kTurnFrame)), kTurn, 0.5 * kDeg);
  // The image's rotation is measured, not copied from the gyro: the turn the gyro got 1 degree
  // short registers at the true one (the window holds both).
  EXPECT_NEAR(std::fabs(with[kTurnFrame].registration12.rotation), kTurn, 0.5 * kDeg);
}

// The same sudden yaw, in the interval of a frame that fails (the camera saw something else): the
// next frame is registered against the one before the failure, two intervals back, and the gyro's
// turn over both intervals (the yaw, and none) is where its rotation is searched. Taking only the
// last interval's turn (none), the yaw was refused and tracking resumed only after a restart.
TEST(AttitudeAidedRegistration, AfterAFailedFrameTheGyrosTurnSpansBothIntervals) {
  const SuddenYawFlight flight = suddenYawFlight();
  const std::vector<sim::FlightPose>& poses = flight.plan.poses;
  cv::Mat1f unrelated(kN, kN);
  cv::RNG(7).fill(unrelated, cv::RNG::UNIFORM, 0.0f, 1.0f);
  cv::GaussianBlur(unrelated, unrelated, cv::Size(0, 0), 3.0);
  Estimator estimator(flight.config);
  std::vector<Estimate> estimates;
  for (std::size_t k = 0; k < poses.size(); ++k) {
    if (k > 0) estimator.setTurn(poses[k].yaw - poses[k - 1].yaw, kGyroRateError * kFrameInterval);
    const cv::Mat1f& frame = static_cast<int>(k) == kTurnFrame ? unrelated : flight.frames[k];
    const std::optional<Estimate> e = estimator.push(frame, kFrameInterval * static_cast<double>(k));
    ASSERT_TRUE(e.has_value());
    estimates.push_back(*e);
  }
  EXPECT_EQ(estimates[kTurnFrame].state, TrackingState::kPredicted);
  const Estimate& next = estimates[kTurnFrame + 1];
  EXPECT_EQ(next.state, TrackingState::kTracking);
  EXPECT_EQ(next.frame_gap, 2);
  EXPECT_NEAR(std::fabs(next.registration12.rotation), kTurn, 0.5 * kDeg);
  // The heading after the gap is the truth's.
  const double yaw_change = std::remainder(next.pose.yaw - estimates[kTurnFrame - 1].pose.yaw, 2.0 * M_PI);
  EXPECT_NEAR(std::fabs(yaw_change), kTurn, 0.5 * kDeg);
  for (std::size_t k = kTurnFrame + 2; k < estimates.size(); ++k) {
    EXPECT_EQ(estimates[k].state, TrackingState::kTracking) << k;
  }
}

}  // namespace
}  // namespace oefmt
