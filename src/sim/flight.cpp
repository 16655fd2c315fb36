// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/sim/flight.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>

#include "oefmt/error.h"
#include "oefmt/sim/renderer.h"

namespace oefmt {
namespace sim {
namespace {

CameraParameters resolveCamera(const FlightOptions& o) {
  if (o.width < 16 || o.height < 16) throw InputError("image size must be at least 16 x 16 px");
  CameraParameters camera;
  Intrinsics& k = camera.intrinsics;
  k.width = o.width;
  k.height = o.height;
  k.fx = o.fx > 0.0 ? o.fx : o.width / (2.0 * std::tan(CV_PI / 6.0));
  k.fy = o.fy > 0.0 ? o.fy : k.fx;
  k.cx = o.cx >= 0.0 ? o.cx : (o.width - 1) / 2.0;
  k.cy = o.cy >= 0.0 ? o.cy : (o.height - 1) / 2.0;
  if (!std::isfinite(k.fx) || !std::isfinite(k.fy) || !std::isfinite(k.cx) || !std::isfinite(k.cy)) {
    throw InputError("intrinsics must be finite");
  }
  camera.distortion = o.distortion;
  return camera;
}

// Mean consecutive ground overlap of the track flown at `altitude`.
double meanOverlapAt(const CameraParameters& camera, TrackConfig track, double altitude) {
  track.altitude = altitude;
  return consecutiveOverlap(camera, makeTrack(track), 0.0).mean;
}

// The altitude at which consecutive frames overlap `target` on average (overlap grows with
// altitude, so bisection).
double altitudeForOverlap(const CameraParameters& camera, const TrackConfig& track, double target) {
  if (!(target > 0.0 && target < 1.0)) throw InputError("overlap must be in (0, 1)");
  const double step = frameSpacing(track);
  double low = std::max(step * 1e-3, 1e-3 - std::min(0.0, track.climb));
  double high = step * 1e4 + std::max(0.0, -track.climb);
  for (int iteration = 0; iteration < 80; ++iteration) {
    const double middle = 0.5 * (low + high);
    (meanOverlapAt(camera, track, middle) < target ? low : high) = middle;
  }
  return 0.5 * (low + high);
}

std::string metres(double value) {
  char text[32];
  std::snprintf(text, sizeof(text), "%.2f m", value);
  return text;
}

// Raised levels must stay below the camera all along the track.
void requireAboveTops(const FlightPlan& plan) {
  const double top = plan.scene.highestTop();
  double lowest = plan.poses.front().position[2];
  for (const FlightPose& pose : plan.poses) lowest = std::min(lowest, pose.position[2]);
  if (lowest > top) return;
  const TrackConfig& t = plan.track;
  std::string message = "the flight's lowest altitude (" + metres(lowest);
  if (t.climb < 0.0) message += ", descending " + metres(-t.climb) + " from " + metres(t.altitude);
  message += ") must be above the highest block top (" + metres(top) + "): raise the altitude, lower the levels";
  message += t.climb < 0.0 ? " or descend less" : "";
  throw InputError(message);
}

// splitmix64's finaliser: a well-mixed 64-bit hash, the same on every machine.
std::uint64_t mix(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

}  // namespace

FlightPlan planFlight(const FlightOptions& o) {
  FlightPlan plan;
  plan.camera = resolveCamera(o);
  const Intrinsics& k = plan.camera.intrinsics;
  plan.track = o.track;
  if (!(plan.track.altitude > 0.0) && !isMoving(plan.track.shape)) {
    plan.track.altitude = kSpinAltitude;  // a spin's frames overlap whatever its altitude
  } else if (!(plan.track.altitude > 0.0)) {
    // Validated here with a stand-in that survives a descent, below with the real value.
    plan.track.altitude = 1.0 + std::max(0.0, -plan.track.climb);
    plan.track.validate();
    plan.track.altitude = altitudeForOverlap(plan.camera, plan.track, o.overlap);
  }
  plan.poses = makeTrack(plan.track);
  const double altitude = plan.track.altitude;
  // Size of a ground pixel at the mean altitude [m]: sets the block and texture scales, so that a
  // climbing flight neither blurs its textures at the start nor aliases them at the top.
  double mean_altitude = 0.0;
  for (const FlightPose& pose : plan.poses) mean_altitude += pose.position[2];
  mean_altitude /= static_cast<double>(plan.poses.size());
  const double ground_pixel = mean_altitude / k.fx;

  SceneConfig& scene = plan.scene;
  scene.seed = o.seed;
  std::vector<double> heights = o.level_heights;
  // Three levels as the authors' scene has three depths of blocks, the inclined one between the
  // flat ones; together with the ground they compete for the dominant correlation peak.
  if (heights.empty()) heights = {0.15 * altitude, 0.30 * altitude, 0.225 * altitude};
  if (o.flat) heights.clear();
  scene.levels.clear();
  for (std::size_t l = 0; l < heights.size(); ++l) {
    BlockLevel level;
    level.height = heights[l];
    level.incline_deg = l + 1 == heights.size() ? o.incline_deg : 0.0;
    level.share = o.raised_share / heights.size();
    scene.levels.push_back(level);
  }
  scene.fill = o.fill;
  scene.cell_size = o.cell_size > 0.0 ? o.cell_size : 0.22 * ground_pixel * k.width;
  scene.texel = o.texel > 0.0 ? o.texel : 0.5 * ground_pixel;
  scene.texture_size = o.texture_size > 0 ? o.texture_size : std::min(4096, 8 * k.width);
  scene.feature_texels = std::max(2.0, scene.texture_size / 40.0);
  scene.texture_files = o.texture_files;
  scene.texture_styles = o.texture_styles;
  // Bricks and tiles of the same size in the image on every layer: a layer nearer the camera
  // shows a smaller part of the world, in texels (mean_altitude - h) / fx * width / texel.
  scene.pattern_texels.clear();
  for (int layer = 0; layer <= static_cast<int>(scene.levels.size()); ++layer) {
    const double h = layer == 0 ? 0.0 : scene.levels[layer - 1].height;
    const double footprint_texels = std::max(0.0, mean_altitude - h) / k.fx * k.width / scene.texel;
    scene.pattern_texels.push_back(std::max(1.0, footprint_texels / kPatternsPerImage));
  }
  if (!(o.contrast >= 0.0 && o.contrast <= 127.5)) throw InputError("contrast must be in [0, 127.5] grey levels");
  scene.texture_std = o.contrast / 255.0;
  scene.walls = o.walls;
  // Everything the camera sees lies inside the union of the ground footprints.
  double x_min = HUGE_VAL, y_min = HUGE_VAL, x_max = -HUGE_VAL, y_max = -HUGE_VAL;
  for (const FlightPose& pose : plan.poses) {
    for (const cv::Point2f& corner : groundFootprint(plan.camera, pose, 0.0)) {
      x_min = std::min(x_min, static_cast<double>(corner.x));
      x_max = std::max(x_max, static_cast<double>(corner.x));
      y_min = std::min(y_min, static_cast<double>(corner.y));
      y_max = std::max(y_max, static_cast<double>(corner.y));
    }
  }
  scene.region = cv::Rect2d(x_min, y_min, x_max - x_min, y_max - y_min);
  scene.validate();

  if (o.supersample < 1 || o.supersample > 8) throw InputError("supersample must be in [1, 8]");
  plan.supersample = o.supersample;
  if (!(o.sensor.noise >= 0.0) || !(o.sensor.brightness >= 0.0 && o.sensor.brightness < 1.0) ||
      !(o.sensor.brightness_period > 0.0) || !(o.sensor.flicker >= 0.0 && o.sensor.flicker < 1.0)) {
    throw InputError("sensor: noise must be >= 0, brightness and flicker in [0, 1), brightness period > 0");
  }
  plan.sensor = o.sensor;
  if (!(o.rate > 0.0) || !(o.start_time > 0.0) || !std::isfinite(o.start_time)) {
    throw InputError("rate and start time must be > 0");
  }
  for (std::size_t i = 0; i < plan.poses.size(); ++i) plan.stamps.push_back(o.start_time + i / o.rate);
  plan.rate = o.rate;
  o.imu.validate();
  o.range.validate();
  plan.tilt = o.tilt;
  plan.imu = o.imu;
  plan.range = o.range;
  if (o.tilt.any()) {
    const VehicleMotion motion = vehicleMotion(plan);
    for (std::size_t i = 0; i < plan.poses.size(); ++i) {
      const FlightPose tilted = motion.poseAt(plan.stamps[i]);
      plan.poses[i].pitch = tilted.pitch;
      plan.poses[i].roll = tilted.roll;
    }
  }

  requireAboveTops(plan);
  plan.ground_overlap = consecutiveOverlap(plan.camera, plan.poses, 0.0);
  double highest_level = 0.0;
  for (const BlockLevel& level : scene.levels) highest_level = std::max(highest_level, level.height);
  plan.top_overlap = consecutiveOverlap(plan.camera, plan.poses, highest_level);
  return plan;
}

double frameGain(const SensorOptions& sensor, std::uint32_t seed, int frame) {
  double gain = 1.0 + sensor.brightness * std::sin(2.0 * CV_PI * frame / sensor.brightness_period);
  if (sensor.flicker > 0.0) {
    // Hashed rather than drawn from a generator seeded by the frame: consecutive seeds give
    // correlated first draws, and the gains must be independent from frame to frame.
    const std::uint64_t h = mix(mix(0xF11C4E5ULL ^ seed) + static_cast<std::uint64_t>(frame));
    const double u = static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0);  // [0, 1)
    gain *= 1.0 + sensor.flicker * (2.0 * u - 1.0);
  }
  return gain;
}

cv::Mat1b sensorImage(const cv::Mat1f& rendered, const SensorOptions& sensor, std::uint32_t seed, int frame) {
  cv::Mat1f image = rendered * frameGain(sensor, seed, frame);
  if (sensor.noise > 0.0) {
    cv::RNG rng((static_cast<std::uint64_t>(seed) << 32) ^ (0x5DEECE66DULL + static_cast<std::uint64_t>(frame)));
    cv::Mat1f noise(image.size());
    rng.fill(noise, cv::RNG::NORMAL, 0.0, sensor.noise);
    image += noise;
  }
  cv::Mat1b out;
  image.convertTo(out, CV_8U, 255.0);  // rounds and saturates
  return out;
}

VehicleMotion vehicleMotion(const FlightPlan& plan) {
  return VehicleMotion(plan.track, plan.rate, plan.stamps.empty() ? 0.0 : plan.stamps.front(), plan.tilt,
                       plan.scene.seed);
}

std::vector<ImuSample> simulateFlightImu(const FlightPlan& plan) {
  if (plan.stamps.empty()) return {};
  return simulateImu(vehicleMotion(plan), plan.stamps.front(), plan.stamps.back(), plan.imu, plan.scene.seed);
}

void renderFlight(const FlightPlan& plan, const FrameSink& sink, std::vector<RangeSample>* ranges) {
  const auto scene = std::make_shared<const Scene>(plan.scene);
  const Renderer renderer(scene, plan.camera, plan.supersample);
  if (ranges) ranges->clear();
  for (std::size_t k = 0; k < plan.poses.size(); ++k) {
    if (ranges) {
      ranges->push_back({plan.stamps[k], simulateRange(*scene, plan.poses[k], plan.range, plan.scene.seed,
                                                        static_cast<int>(k))});
    }
    const RenderedFrame frame = renderer.render(plan.poses[k]);
    sink(static_cast<int>(k), sensorImage(frame.image, plan.sensor, plan.scene.seed, static_cast<int>(k)),
         frame.layers);
  }
}

std::vector<std::string> groundTruthHeader(const FlightPlan& plan) {
  const TrackConfig& t = plan.track;
  const std::string shape =
      isMoving(t.shape) ? ", length " + std::to_string(t.length) + " m, altitude " + std::to_string(t.altitude) +
                              " m, climb " + std::to_string(t.climb) + " m"
                        : " at the origin, altitude " + std::to_string(t.altitude) + " m, yaw turning " +
                              std::to_string(t.spin_rate * 180.0 / CV_PI) + " deg per frame";
  return {
      "oefmt_simulate ground truth, one line per frame: t x y z qx qy qz qw",
      "t: seconds (same stamps as timestamps.txt and the bag); x y z: metres",
      "world frame (REP-103, ENU): x east, y north, z up; ground plane at z = 0",
      plan.tilt.any() ? "pose of the camera body (base_link): position and attitude (tilted as a multirotor)"
                      : "pose of the camera body (base_link): position and yaw about z (roll = pitch = 0)",
      plan.tilt.any() ? "the camera looks down the body's -z: base_link -> camera optical frame is a 180 deg turn about x"
                      : "the camera looks straight down: base_link -> camera optical frame is a 180 deg turn about x",
      "(quaternion x=1 y=0 z=0 w=0), so at yaw 0 image right = +x (east), image up = +y (north)",
      std::string("track ") + toString(t.shape) + ", " + std::to_string(plan.poses.size()) + " frames" + shape,
  };
}

}  // namespace sim
}  // namespace oefmt
