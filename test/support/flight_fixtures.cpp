// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/flight_fixtures.h"

#include <cmath>
#include <mutex>
#include <optional>

#include "oefmt/sim/similarity_views.h"
#include "oefmt/sim/texture.h"

namespace oefmt {
namespace test {
namespace {

// Image position, relative to the texture centre, of the ground point (east, north).
cv::Point2d texturePosition(double east, double north) { return {east, -north}; }

// Turns a y-down vector counter-clockwise on screen by a (the renderer's R).
cv::Point2d turnOnScreen(const cv::Point2d& v, double a) {
  const double c = std::cos(a), s = std::sin(a);
  return {c * v.x + s * v.y, -s * v.x + c * v.y};
}

}  // namespace

cv::Mat1f cameraView(const cv::Mat1f& texture, const CameraState& state, int n) {
  const cv::Point2d centre(texture.cols / 2.0, texture.rows / 2.0);
  // The camera sees the ground point under it at the image centre; yawing the camera
  // counter-clockwise turns the content clockwise; climbing shrinks it.
  sim::ViewMotion motion;
  motion.rotation = -state.yaw;
  motion.zoom = 1.0 / state.altitude;
  motion.shift = turnOnScreen(-texturePosition(state.east, state.north), motion.rotation) * motion.zoom;
  return sim::renderView(texture, centre, motion, n);
}

Flight renderFlight(const cv::Mat1f& texture, const std::vector<CameraState>& states, int n) {
  Flight flight;
  flight.truth = states;
  for (const CameraState& s : states) flight.frames.push_back(cameraView(texture, s, n));
  return flight;
}

std::vector<CameraState> straightLine(int frames, double east_step, double north_step,
                                      double yaw_step, double altitude_step) {
  std::vector<CameraState> states(frames);
  for (int k = 1; k < frames; ++k) {
    states[k] = states[k - 1];
    states[k].east += east_step;
    states[k].north += north_step;
    states[k].yaw += yaw_step;
    states[k].altitude *= altitude_step;
  }
  return states;
}

Flight renderTwoLayerFlight(const cv::Mat1f& ground, const cv::Mat1f& roofs, const cv::Mat1f& mask,
                            const std::vector<cv::Point2d>& ground_positions,
                            double roof_speed_ratio, int n) {
  Flight flight;
  const cv::Point2d centre(ground.cols / 2.0, ground.rows / 2.0);
  for (const cv::Point2d& p : ground_positions) {
    const cv::Point2d ground_shift = -texturePosition(p.x, p.y);
    flight.frames.push_back(sim::renderTwoLayerView(ground, roofs, mask, centre, ground_shift,
                                                    ground_shift * roof_speed_ratio, n));
    CameraState state;
    state.east = p.x;
    state.north = p.y;
    flight.truth.push_back(state);
  }
  return flight;
}

const cv::Mat1f& flightTexture() {
  static std::once_flag once;
  static cv::Mat1f texture;
  std::call_once(once, [] {
    texture = sim::proceduralTexture(cv::Size(2048, 2048), 31, sim::TextureStyle::kCells, 40.0);
  });
  return texture;
}

sim::FlightOptions tiledFigureEight() {
  sim::FlightOptions options;
  options.track.shape = sim::TrackShape::kEight;
  options.track.length = 880.0;  // oefmt_simulate's figure-8
  options.track.frames = 300;
  options.texture_styles = {sim::TextureStyle::kTiles};
  options.walls = true;
  options.seed = 22;
  return options;
}

sim::FlightOptions roofLine(unsigned seed) {
  sim::FlightOptions options;
  options.track.shape = sim::TrackShape::kLine;
  options.track.frames = 100;
  options.track.length = 200.0;
  options.track.altitude = 20.0;
  options.track.heading = sim::HeadingMode::kTrack;
  options.track.line_direction = 30.0 * M_PI / 180.0;
  options.level_heights = {8.0};
  options.walls = true;
  options.seed = seed;
  return options;
}

sim::FlightOptions weakTextureFlight(sim::TrackShape shape, unsigned seed) {
  sim::FlightOptions options;
  options.track.shape = shape;
  options.contrast = 10.0;
  options.sensor.noise = 5.0 / 255.0;
  options.sensor.flicker = 0.1;
  options.seed = seed;
  return options;
}

sim::FlightPlan plannedFlight(const sim::FlightOptions& options, int frames) {
  sim::FlightPlan plan = sim::planFlight(options);
  plan.poses.resize(frames);
  plan.stamps.resize(frames);
  return plan;
}

std::vector<cv::Mat1b> renderPlan(const sim::FlightPlan& plan) {
  std::vector<cv::Mat1b> frames;
  sim::renderFlight(plan, [&frames](int, const cv::Mat1b& image, const cv::Mat1b&) { frames.push_back(image); });
  return frames;
}

EstimatorConfig simulatedFlightConfig(const sim::FlightPlan& plan) {
  EstimatorConfig config;
  config.registration.fft_planning = FftPlanning::kEstimate;
  config.initial_altitude = plan.track.altitude;
  config.working_fx = plan.camera.intrinsics.fx;
  return config;
}

void appendPositions(const Pose4& estimated, const sim::FlightPose& true_pose, std::size_t index,
                     StampedTrajectory& estimate, StampedTrajectory& truth) {
  StampedPose p;
  p.stamp = static_cast<double>(index);
  p.position = Eigen::Vector3d(estimated.x, estimated.y, estimated.z);
  estimate.push_back(p);
  StampedPose t;
  t.stamp = p.stamp;
  t.position = Eigen::Vector3d(true_pose.position[0], true_pose.position[1], true_pose.position[2]);
  truth.push_back(t);
}

FlownPlan flyPlan(Estimator& estimator, const sim::FlightPlan& plan, const std::vector<cv::Mat1b>& frames) {
  FlownPlan flown;
  double previous_yaw = 0.0;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    const std::optional<Estimate> e = estimator.push(frames[k], plan.stamps[k]);
    if (!e) {
      flown.refused.push_back(k);
      continue;
    }
    if (k > 0) {
      flown.heading_step_errors.push_back(
          std::remainder((e->pose.yaw - previous_yaw) - (plan.poses[k].yaw - plan.poses[k - 1].yaw), 2.0 * M_PI));
    }
    previous_yaw = e->pose.yaw;
    appendPositions(e->pose, plan.poses[k], k, flown.estimate, flown.truth);
  }
  return flown;
}

}  // namespace test
}  // namespace oefmt
