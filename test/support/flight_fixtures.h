// SPDX-License-Identifier: GPL-3.0-or-later
// Test flights: views of a down-looking camera moving over a flat (or two-layer) textured scene,
// with the ground truth in the estimator's world conventions.
#pragma once

#include <cstddef>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/estimation/estimator.h"
#include "oefmt/estimation/estimator_config.h"
#include "oefmt/evaluation/evaluation.h"
#include "oefmt/sim/camera_model.h"
#include "oefmt/sim/flight.h"
#include "oefmt/estimation/pose.h"

namespace oefmt {
namespace test {

/// A camera state over the texture. east/north are ground distances from the texture centre in
/// texture pixels (texture x = east, texture y = south); yaw turns the camera counter-clockwise
/// seen from above; altitude is relative to the first frame's (1 = start). At altitude 1 one
/// image pixel covers one texture pixel, so fx = altitude_0 = n makes world units texture pixels.
struct CameraState {
  double east = 0.0;
  double north = 0.0;
  double yaw = 0.0;
  double altitude = 1.0;
};

/// The n x n view of the camera at `state`.
cv::Mat1f cameraView(const cv::Mat1f& texture, const CameraState& state, int n);

struct Flight {
  std::vector<cv::Mat1f> frames;
  std::vector<CameraState> truth;
};

/// Renders one view per state.
Flight renderFlight(const cv::Mat1f& texture, const std::vector<CameraState>& states, int n);

/// States along a straight line: `steps` steps of (east, north) ground pixels each, starting at
/// the origin, optionally turning by yaw_step and scaling the altitude by altitude_step per step.
std::vector<CameraState> straightLine(int frames, double east_step, double north_step,
                                      double yaw_step = 0.0, double altitude_step = 1.0);

/// A two-depth scene flown at constant heading and altitude: the raised layer (roofs, given by
/// mask) is nearer to the camera, so its content moves `roof_speed_ratio` times as far as the
/// ground's. ground_positions are the camera's (east, north) positions in ground pixels.
Flight renderTwoLayerFlight(const cv::Mat1f& ground, const cv::Mat1f& roofs, const cv::Mat1f& mask,
                            const std::vector<cv::Point2d>& ground_positions,
                            double roof_speed_ratio, int n);

/// The scene texture of the flight tests (2048 x 2048, cells, seeded).
const cv::Mat1f& flightTexture();

/// The weakest texture the estimator is asked to track: grey std 10 of 255, sensor noise of 5 grey
/// levels and a brightness flicker of +-10 % between frames, over the simulator's default scene.
sim::FlightOptions weakTextureFlight(sim::TrackShape shape, unsigned seed);

/// The generalization corpus's `eight-tiles`: oefmt_simulate's figure-8 over tiles on every layer,
/// walls in view, consecutive frames overlapping 78 % (seed 22).
sim::FlightOptions tiledFigureEight();

/// The generalization corpus's strong-parallax lines (`line-parallax-s2` is seed 34): a level
/// 200 m line at 20 m over blocks whose tops stand at 8 m, walls in view, the heading on the
/// track, 100 frames.
sim::FlightOptions roofLine(unsigned seed);

/// The simulator's plan for `options`, cut to its first `frames` frames.
sim::FlightPlan plannedFlight(const sim::FlightOptions& options, int frames);

/// Every frame of a simulator flight plan as its camera gives it (sim::renderFlight).
std::vector<cv::Mat1b> renderPlan(const sim::FlightPlan& plan);

/// The estimator's configuration for a simulated flight: its true initial altitude (metric
/// output), its camera's focal length, FFT plans estimated (fast to make).
EstimatorConfig simulatedFlightConfig(const sim::FlightPlan& plan);

/// Appends frame `index`'s estimated position and the simulated flight's true one, both stamped
/// with the index (for an evaluation that associates by index).
void appendPositions(const Pose4& estimated, const sim::FlightPose& true_pose, std::size_t index,
                     StampedTrajectory& estimate, StampedTrajectory& truth);

/// A simulator flight flown through an estimator.
struct FlownPlan {
  /// Each accepted frame's heading step (from the last accepted frame's) minus the true one
  /// [rad, wrapped to (-pi, pi]].
  std::vector<double> heading_step_errors;
  StampedTrajectory estimate, truth;  ///< accepted frames, stamped by index (appendPositions)
  std::vector<std::size_t> refused;   ///< frames the estimator did not take
};

/// Pushes `frames` (the plan's, in order) through `estimator` at the plan's stamps.
FlownPlan flyPlan(Estimator& estimator, const sim::FlightPlan& plan, const std::vector<cv::Mat1b>& frames);

}  // namespace test
}  // namespace oefmt
