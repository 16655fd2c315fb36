// SPDX-License-Identifier: GPL-3.0-or-later
// A whole simulated flight: options with automatic defaults resolved into a plan (camera, track,
// scene, stamps), rendering of every frame and the simulated sensor (noise, brightness, flicker).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/io/dataset.h"
#include "oefmt/sim/camera_model.h"
#include "oefmt/sim/scene.h"
#include "oefmt/sim/track.h"
#include "oefmt/sim/vehicle_motion.h"
#include "oefmt/sim/vehicle_sensors.h"

namespace oefmt {
namespace sim {

/// What the simulated sensor adds to a rendered frame.
struct SensorOptions {
  double noise = 0.0;              ///< std of additive Gaussian noise, intensity units (1 = white)
  double brightness = 0.0;         ///< relative amplitude of the frame gain's variation
  double brightness_period = 50.0; ///< frames per period of the gain's sine
  /// Random per-frame gain factor, uniform in [1 - flicker, 1 + flicker] (deterministic for seed
  /// and frame), times the sine's gain.
  double flicker = 0.0;
};

/// Every option of a flight. Zero (or empty) means "choose automatically", as documented.
struct FlightOptions {
  FlightOptions() { track.altitude = 0.0; }
  /// track.altitude 0 (default): chosen so frames overlap `overlap`; a spin's: kSpinAltitude.
  TrackConfig track;
  double overlap = 0.78;      ///< target mean overlap of consecutive frames on the ground
  int width = 512;            ///< image size [px]
  int height = 512;
  double fx = 0.0;            ///< [px]; 0: a 60 degree horizontal field of view
  double fy = 0.0;            ///< [px]; 0: fx
  double cx = -1.0;           ///< [px]; < 0: the image centre (width - 1) / 2
  double cy = -1.0;           ///< [px]; < 0: (height - 1) / 2
  Distortion distortion;      ///< k1, k2 (p1, p2) of the rendered lens
  std::uint32_t seed = 1;
  /// Raised levels' heights [m]; empty: 0.15, 0.30 and 0.225 of the altitude (the last inclined).
  std::vector<double> level_heights;
  bool flat = false;          ///< ground plane only (no raised levels)
  double incline_deg = 6.0;   ///< tilt of the last level's terraces [deg]
  double raised_share = 1.0;  ///< fraction of terraces raised, split evenly among the levels
  double fill = 0.8;          ///< probability that a cell of a raised terrace has a top
  double cell_size = 0.0;     ///< block pitch [m]; 0: 0.22 of the mean ground footprint's width
  double texel = 0.0;         ///< texture resolution [m]; 0: half a ground pixel at mean altitude
  int texture_size = 0;       ///< procedural texture side [texels]; 0: 8 * width, at most 4096
  std::vector<std::string> texture_files;  ///< per layer (0 ground, 1.. levels), empty = procedural
  /// Procedural style per layer (ground first; beyond the list the last one); empty: kMixed.
  std::vector<TextureStyle> texture_styles;
  double contrast = 0.0;      ///< grey std [grey levels of 255] of every texture; 0: as made
  bool walls = false;         ///< tops are lids of solid prisms whose side walls are rendered
  int supersample = 2;        ///< s x s rays per pixel
  SensorOptions sensor;
  double rate = 5.0;          ///< frames per second [Hz]
  double start_time = 1.0;    ///< stamp of the first frame [s] (> 0: ROS bags need it)
  TiltOptions tilt;           ///< roll and pitch of the body (default: level)
  ImuOptions imu;
  RangeOptions range;
};

/// Altitude of a spin without a given altitude [m] (a spin has no overlap to choose it by).
constexpr double kSpinAltitude = 20.0;

/// Bricks or tiles per image width (on their layer, at the mean altitude): many repetitions, so
/// that phase correlation sees a strictly periodic pattern.
constexpr double kPatternsPerImage = 16.0;

/// The resolved flight.
struct FlightPlan {
  CameraParameters camera;
  TrackConfig track;
  SceneConfig scene;
  int supersample = 2;
  SensorOptions sensor;
  std::vector<FlightPose> poses;
  std::vector<double> stamps;         ///< [s]
  OverlapStatistics ground_overlap;   ///< consecutive frames, on the ground plane
  OverlapStatistics top_overlap;      ///< consecutive frames, on the highest level's plane
  double rate = 5.0;                  ///< [Hz]
  TiltOptions tilt;
  ImuOptions imu;
  RangeOptions range;
};

/// Resolves the automatic choices and computes poses, stamps and overlaps.
/// Throws InputError naming the first invalid option.
FlightPlan planFlight(const FlightOptions& options);

/// The camera's gain for frame k (1 without brightness change or flicker).
double frameGain(const SensorOptions& sensor, std::uint32_t seed, int frame);

/// Applies gain and noise (deterministic for seed and frame) and converts to 8 bits.
cv::Mat1b sensorImage(const cv::Mat1f& rendered, const SensorOptions& sensor, std::uint32_t seed, int frame);

/// Receives frame k: the 8-bit image, and the renderer's layer map.
using FrameSink = std::function<void(int frame, const cv::Mat1b& image, const cv::Mat1b& layers)>;

/// Builds the scene and renderer of the plan, renders every frame in order and calls `sink`;
/// with `ranges`, also gives the rangefinder's reading at every frame.
void renderFlight(const FlightPlan& plan, const FrameSink& sink, std::vector<RangeSample>* ranges = nullptr);

/// The vehicle's motion between and beyond the frames (what the plan's poses sample).
VehicleMotion vehicleMotion(const FlightPlan& plan);

/// The IMU's samples over the flight, from its first frame's stamp to its last's.
std::vector<ImuSample> simulateFlightImu(const FlightPlan& plan);

/// The comment lines of groundtruth.tum: frame, units and conventions.
std::vector<std::string> groundTruthHeader(const FlightPlan& plan);

}  // namespace sim
}  // namespace oefmt
