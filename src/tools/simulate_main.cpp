// SPDX-License-Identifier: GPL-3.0-or-later
// oefmt_simulate: renders a flight of a down-looking camera over a multi-depth textured scene and
// writes it in the authors' dataset layout with ground truth (and optionally as a ROS bag).
#include <chrono>
#include <cmath>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "command_line.h"
#include "oefmt/error.h"
#include "oefmt/ros/bag_io.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/folder_writer.h"
#include "progress.h"

namespace {

const char* const kUsage = R"(usage: oefmt_simulate [options] OUTPUT_DIR

Renders a flight of a pinhole camera looking straight down at a textured ground plane with raised
block tops at further heights (the last level's terraces inclined; optionally solid blocks with
walls), and writes OUTPUT_DIR in the o-eFMT authors' layout: Images/0001.png..., imageList.txt,
timestamps.txt (seconds), cam_param.yaml, plus groundtruth.tum (t x y z qx qy qz qw; world x
east, y north, z up).
Deterministic for a given seed. Defaults: the paper's circle (491 m, 200 frames, 512x512).

track:
  --track circle|eight|line|spin
                             shape (default circle); spin: no motion, the camera turns on the
                             spot at the origin
  --length M                 path length [m] (default circle 491, eight 880, line 200; not spin)
  --frames N                 frames (default circle 200, eight 300, line 100, spin 100); loops
                             repeat the first frame at the end
  --altitude M               height above the ground [m] (default: from --overlap; spin 20)
  --overlap F                target mean overlap of consecutive frames on the ground (0.78;
                             not spin)
  --climb M                  altitude change [m], negative for a descent (default 0; not spin)
  --climb-profile ramp|hill  how a line changes altitude: ramp = linearly to altitude + climb
                             (default), hill = smoothly to it half-way and back; loops: hill
  --spin-rate DEG            yaw change per frame of a spin, either sign (default 6)
  --heading fixed|track      yaw fixed, or following the direction of motion (default fixed)
  --yaw DEG                  fixed yaw, or offset to the direction of motion (default 0)
  --direction DEG            direction of a line track, from east counter-clockwise (default 0)
camera:
  --size PX                  width and height (default 512)
  --width PX, --height PX
  --fx PX, --fy PX           focal lengths (default: 60 deg horizontal field of view; fy = fx)
  --cx PX, --cy PX           principal point (default: image centre)
  --k1 K, --k2 K             radial distortion rendered and written to cam_param/CameraInfo
                             (a barrel lens sees wider: without --altitude it flies lower)
scene:
  --seed N                   scene and noise seed (default 1)
  --levels H1,H2,...         raised levels' heights [m] (default 0.15, 0.30 and 0.225 of the
                             altitude)
  --flat                     ground plane only, no raised levels
  --incline DEG              tilt of the last level's terraces (default 6)
  --raised F                 fraction of the terraces raised, split among the levels (1)
  --fill F                   probability that a cell of a raised terrace has a top (0.8)
  --cell M                   block pitch [m] (default 0.22 of the ground footprint's width at
                             the mean altitude)
  --texel M                  texture resolution [m] (default half a ground pixel at the mean
                             altitude)
  --texture-size N           procedural texture side [texels] (default 8 x width, <= 4096)
  --texture LAYER=FILE       image file as texture of a layer (0 ground, 1.. levels); repeatable
  --texture-style S[,S2,...] procedural texture per layer, ground first (the last one for the
                             layers beyond the list): mixed (default: ground cells, level 1
                             stripes, level 2 noise, ...), cells, stripes, noise, natural
                             (photo-like, 1/f spectrum), brick, tiles (strictly periodic, about
                             16 bricks or tiles per image width)
  --contrast STD             rescale every texture to this grey std [grey levels of 255] around
                             mid grey (default: as made); the summary prints the frames' std
  --walls                    solid blocks: tops stand on the ground and their side walls are
                             rendered (default: tops without walls)
rendering and sensor:
  --supersample N            N x N rays per pixel (default 2)
  --noise SIGMA              Gaussian noise std, intensity 0..1 (default 0; 5 grey levels =
                             0.0196)
  --noise-grey SIGMA         the same in grey levels of 255 (= --noise SIGMA/255)
  --brightness A             frame gain 1 + A sin(2 pi k / period) (default 0)
  --brightness-period N      frames (default 50)
  --flicker A                random gain per frame, uniform in [1 - A, 1 + A], times the sine's
                             (default 0)
  --threads N                rendering threads (default: all cores)
time and output:
  --rate HZ                  frame rate (default 5)
  --start-time S             stamp of the first frame (default 1.0)
  --bag FILE                 also write a ROS bag (sensor_msgs/Image + CameraInfo)
  --bag-compression C        none, lz4 or bz2 (default none)
  --image-topic T            (default /camera/image_raw)
  --info-topic T             (default /camera/camera_info)
  --frame-id F               (default camera_optical)
  --quiet                    print nothing but errors
  -h, --help
exit codes: 0 success, 1 write failure, 2 invalid option)";

using oefmt::tools::Arguments;
using oefmt::tools::numberList;

constexpr double kDeg = CV_PI / 180.0;

struct Command {
  oefmt::sim::FlightOptions flight;
  std::string output;
  std::string bag;
  oefmt::BagWriterOptions bag_options;
  int threads = -1;
  bool quiet = false;
  bool help = false;
};

Command parse(int argc, char** argv) {
  Command command;
  oefmt::sim::FlightOptions& f = command.flight;
  bool length_set = false, frames_set = false, overlap_set = false, spin_rate_set = false,
       profile_set = false;
  Arguments args(argc, argv);
  while (!args.done()) {
    const std::string arg = args.take();
    if (arg == "-h" || arg == "--help") {
      command.help = true;
      return command;
    } else if (arg == "--track") {
      f.track.shape = oefmt::sim::trackShapeFromString(args.value(arg));
    } else if (arg == "--length") {
      f.track.length = args.number(arg);
      length_set = true;
    } else if (arg == "--frames") {
      f.track.frames = args.integer(arg);
      frames_set = true;
    } else if (arg == "--altitude") {
      f.track.altitude = args.number(arg);
      if (!(f.track.altitude > 0.0)) throw oefmt::InputError("--altitude must be > 0");
    } else if (arg == "--overlap") {
      f.overlap = args.number(arg);
      overlap_set = true;
    } else if (arg == "--climb") {
      f.track.climb = args.number(arg);
    } else if (arg == "--climb-profile") {
      const std::string profile = args.value(arg);
      if (profile != "ramp" && profile != "hill") throw oefmt::InputError("--climb-profile must be ramp or hill");
      f.track.climb_profile = profile == "ramp" ? oefmt::sim::ClimbProfile::kRamp : oefmt::sim::ClimbProfile::kHill;
      profile_set = true;
    } else if (arg == "--spin-rate") {
      f.track.spin_rate = args.number(arg) * kDeg;
      if (!(std::fabs(f.track.spin_rate) < CV_PI)) throw oefmt::InputError("--spin-rate must be in (-180, 180) deg");
      spin_rate_set = true;
    } else if (arg == "--heading") {
      const std::string mode = args.value(arg);
      if (mode != "fixed" && mode != "track") throw oefmt::InputError("--heading must be fixed or track");
      f.track.heading = mode == "fixed" ? oefmt::sim::HeadingMode::kFixed : oefmt::sim::HeadingMode::kTrack;
    } else if (arg == "--yaw") {
      f.track.yaw = args.number(arg) * kDeg;
    } else if (arg == "--direction") {
      f.track.line_direction = args.number(arg) * kDeg;
    } else if (arg == "--size") {
      f.width = f.height = args.integer(arg);
    } else if (arg == "--width") {
      f.width = args.integer(arg);
    } else if (arg == "--height") {
      f.height = args.integer(arg);
    } else if (arg == "--fx") {
      f.fx = args.number(arg);
    } else if (arg == "--fy") {
      f.fy = args.number(arg);
    } else if (arg == "--cx") {
      f.cx = args.number(arg);
    } else if (arg == "--cy") {
      f.cy = args.number(arg);
    } else if (arg == "--k1") {
      f.distortion.k1 = args.number(arg);
    } else if (arg == "--k2") {
      f.distortion.k2 = args.number(arg);
    } else if (arg == "--seed") {
      const int seed = args.integer(arg);
      if (seed < 0) throw oefmt::InputError("--seed must be >= 0");
      f.seed = static_cast<std::uint32_t>(seed);
    } else if (arg == "--levels") {
      f.level_heights = numberList(arg, args.value(arg));
    } else if (arg == "--flat") {
      f.flat = true;
    } else if (arg == "--incline") {
      f.incline_deg = args.number(arg);
    } else if (arg == "--raised") {
      f.raised_share = args.number(arg);
    } else if (arg == "--fill") {
      f.fill = args.number(arg);
    } else if (arg == "--cell") {
      f.cell_size = args.number(arg);
    } else if (arg == "--texel") {
      f.texel = args.number(arg);
    } else if (arg == "--texture-size") {
      f.texture_size = args.integer(arg);
    } else if (arg == "--texture") {
      const std::string text = args.value(arg);
      const auto equals = text.find('=');
      char* end = nullptr;
      const long layer = equals == std::string::npos ? -1 : std::strtol(text.c_str(), &end, 10);
      if (layer < 0 || layer > 16 || end != text.c_str() + equals || equals + 1 >= text.size()) {
        throw oefmt::InputError("--texture needs LAYER=FILE with LAYER 0 (ground), 1, 2, ...");
      }
      if (f.texture_files.size() <= static_cast<std::size_t>(layer)) f.texture_files.resize(layer + 1);
      f.texture_files[layer] = text.substr(equals + 1);
    } else if (arg == "--texture-style") {
      f.texture_styles.clear();
      std::stringstream list(args.value(arg));
      std::string name;
      while (std::getline(list, name, ',')) {
        try {
          f.texture_styles.push_back(oefmt::sim::textureStyleFromString(name));
        } catch (const oefmt::InputError& e) {
          throw oefmt::InputError(std::string("--texture-style: ") + e.what());
        }
      }
      if (f.texture_styles.empty()) throw oefmt::InputError("--texture-style needs a style");
    } else if (arg == "--contrast") {
      f.contrast = args.number(arg);
      if (!(f.contrast > 0.0 && f.contrast <= 127.5)) throw oefmt::InputError("--contrast must be in (0, 127.5] grey levels");
    } else if (arg == "--walls") {
      f.walls = true;
    } else if (arg == "--supersample") {
      f.supersample = args.integer(arg);
    } else if (arg == "--noise") {
      f.sensor.noise = args.number(arg);
    } else if (arg == "--noise-grey") {
      f.sensor.noise = args.number(arg) / 255.0;
      if (!(f.sensor.noise >= 0.0)) throw oefmt::InputError("--noise-grey must be >= 0");
    } else if (arg == "--brightness") {
      f.sensor.brightness = args.number(arg);
    } else if (arg == "--brightness-period") {
      f.sensor.brightness_period = args.number(arg);
    } else if (arg == "--flicker") {
      f.sensor.flicker = args.number(arg);
      if (!(f.sensor.flicker >= 0.0 && f.sensor.flicker < 1.0)) throw oefmt::InputError("--flicker must be in [0, 1)");
    } else if (arg == "--threads") {
      command.threads = args.integer(arg);
      if (command.threads < 1) throw oefmt::InputError("--threads must be >= 1");
    } else if (arg == "--rate") {
      f.rate = args.number(arg);
    } else if (arg == "--start-time") {
      f.start_time = args.number(arg);
    } else if (arg == "--bag") {
      command.bag = args.value(arg);
    } else if (arg == "--bag-compression") {
      command.bag_options.compression = args.value(arg);
    } else if (arg == "--image-topic") {
      command.bag_options.image_topic = args.value(arg);
    } else if (arg == "--info-topic") {
      command.bag_options.camera_info_topic = args.value(arg);
    } else if (arg == "--frame-id") {
      command.bag_options.frame_id = args.value(arg);
    } else if (arg == "--quiet") {
      command.quiet = true;
    } else if (!arg.empty() && arg[0] == '-') {
      throw oefmt::InputError("unknown option '" + arg + "' (see --help)");
    } else if (command.output.empty()) {
      command.output = arg;
    } else {
      throw oefmt::InputError("more than one output folder given ('" + command.output + "', '" + arg + "')");
    }
  }
  if (command.output.empty()) throw oefmt::InputError("no OUTPUT_DIR given (see --help)");
  using oefmt::sim::TrackShape;
  const TrackShape shape = f.track.shape;
  if (shape == TrackShape::kSpin) {
    if (length_set) throw oefmt::InputError("--length does not apply to --track spin (the camera stays at the origin)");
    if (overlap_set) {
      throw oefmt::InputError("--overlap does not apply to --track spin (the camera does not move): give --altitude "
                              "(default 20 m)");
    }
    if (f.track.climb != 0.0) throw oefmt::InputError("--climb does not apply to --track spin");
    if (profile_set) throw oefmt::InputError("--climb-profile does not apply to --track spin");
    if (f.track.heading == oefmt::sim::HeadingMode::kTrack) {
      throw oefmt::InputError("--heading track needs a moving track, not spin");
    }
  } else if (spin_rate_set) {
    throw oefmt::InputError("--spin-rate applies to --track spin only");
  }
  if (profile_set && f.track.climb_profile == oefmt::sim::ClimbProfile::kRamp && shape != TrackShape::kLine) {
    throw oefmt::InputError("--climb-profile ramp needs --track line (a loop comes back to its start: hill)");
  }
  if (!length_set) f.track.length = shape == TrackShape::kEight ? 880.0 : shape == TrackShape::kLine ? 200.0 : shape == TrackShape::kSpin ? 0.0 : 491.0;
  if (!frames_set) f.track.frames = shape == TrackShape::kEight ? 300 : shape == TrackShape::kCircle ? 200 : 100;
  return command;
}

void printTextures(const oefmt::sim::SceneConfig& scene) {
  std::printf("textures   ");
  bool periodic = false;
  for (std::size_t layer = 0; layer <= scene.levels.size(); ++layer) {
    std::printf(layer == 0 ? " ground " : ", %zu ", layer);
    if (layer < scene.texture_files.size() && !scene.texture_files[layer].empty()) {
      std::printf("%s", scene.texture_files[layer].c_str());
      continue;
    }
    const auto style = oefmt::sim::layerTextureStyle(scene.texture_styles, static_cast<int>(layer));
    std::printf("%s", oefmt::sim::toString(style));
    const double pattern = scene.patternTexels(static_cast<int>(layer));
    if (style == oefmt::sim::TextureStyle::kBrick) {
      const cv::Size brick = oefmt::sim::brickSize(pattern);
      std::printf(" %dx%d", brick.width, brick.height);
      periodic = true;
    } else if (style == oefmt::sim::TextureStyle::kTiles) {
      std::printf(" %d", oefmt::sim::tileSide(pattern));
      periodic = true;
    }
  }
  if (periodic) std::printf(" (brick, tile sizes in texels)");
  if (scene.texture_std > 0.0) std::printf("; rescaled to grey std %.1f", scene.texture_std * 255.0);
  std::printf("\n");
}

void printPlan(const oefmt::sim::FlightPlan& plan, const Command& command) {
  const oefmt::Intrinsics& k = plan.camera.intrinsics;
  const auto& t = plan.track;
  if (oefmt::sim::isMoving(t.shape)) {
    std::printf("track       %s, %zu frames, %.1f m (%.3f m per frame), heading %s, yaw %.1f deg\n",
                oefmt::sim::toString(t.shape), plan.poses.size(), t.length, oefmt::sim::frameSpacing(t),
                t.heading == oefmt::sim::HeadingMode::kFixed ? "fixed" : "along track", t.yaw / kDeg);
    const bool hill = oefmt::sim::resolvedClimbProfile(t) == oefmt::sim::ClimbProfile::kHill;
    std::printf("altitude    %.3f m%s, climb %.2f m%s\n", t.altitude,
                command.flight.track.altitude > 0.0 ? "" : " (from the target overlap)", t.climb,
                t.climb == 0.0 ? "" : hill ? " (there and back, 1 - cos)" : " (linear)");
  } else {
    std::printf("track       spin at the origin, %zu frames, yaw %.1f deg turning %.2f deg per frame\n",
                plan.poses.size(), t.yaw / kDeg, t.spin_rate / kDeg);
    std::printf("altitude    %.3f m%s\n", t.altitude, command.flight.track.altitude > 0.0 ? "" : " (the spin's default)");
  }
  std::printf("camera      %dx%d, fx %.2f fy %.2f cx %.2f cy %.2f, k1 %.4g k2 %.4g, ground pixel %.4f m at start\n",
              k.width, k.height, k.fx, k.fy, k.cx, k.cy, plan.camera.distortion.k1, plan.camera.distortion.k2,
              t.altitude / k.fx);
  std::printf("scene       seed %u, ground + %zu levels:", plan.scene.seed, plan.scene.levels.size());
  for (const auto& level : plan.scene.levels) std::printf(" %.2f m (incline %.1f deg)", level.height, level.incline_deg);
  std::printf("%s\n            cell %.3f m, texel %.4f m, textures %d px, supersample %dx%d\n",
              plan.scene.walls ? ", solid blocks with walls" : "", plan.scene.cell_size, plan.scene.texel,
              plan.scene.texture_size, plan.supersample, plan.supersample);
  printTextures(plan.scene);
  const oefmt::sim::SensorOptions& sensor = plan.sensor;
  std::printf("sensor      noise %.4g (%.1f grey levels), brightness %.3g (period %.3g frames), flicker %.3g\n",
              sensor.noise, sensor.noise * 255.0, sensor.brightness, sensor.brightness_period, sensor.flicker);
  std::printf("overlap     consecutive frames on the ground: min %.1f %%, mean %.1f %%, max %.1f %%\n",
              plan.ground_overlap.min * 100, plan.ground_overlap.mean * 100, plan.ground_overlap.max * 100);
  std::printf("            on the highest level:             min %.1f %%, mean %.1f %%, max %.1f %%\n",
              plan.top_overlap.min * 100, plan.top_overlap.mean * 100, plan.top_overlap.max * 100);
  std::printf("time        %.3f .. %.3f s at %.3g Hz\n", plan.stamps.front(), plan.stamps.back(), command.flight.rate);
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  Command command;
  try {
    command = parse(argc, argv);
  } catch (const oefmt::InputError& e) {
    std::fprintf(stderr, "oefmt_simulate: %s\n", e.what());
    return 2;
  }
  if (command.help) {
    std::puts(kUsage);
    return 0;
  }
  if (command.threads > 0) cv::setNumThreads(command.threads);
  const auto start = std::chrono::steady_clock::now();
  try {
    const oefmt::sim::FlightPlan plan = oefmt::sim::planFlight(command.flight);
    if (!command.quiet) printPlan(plan, command);
    // Even when quiet: a flight whose frames barely overlap (a steep climb from a low start,
    // too few frames) cannot be followed by any frame-to-frame odometry.
    constexpr double kLowOverlap = 0.3;
    if (plan.top_overlap.min < kLowOverlap) {
      std::fprintf(stderr,
                   "oefmt_simulate: warning: consecutive frames overlap only %.0f %% at worst (on the "
                   "highest level): raise --altitude or --frames, or lower --climb\n",
                   std::max(0.0, plan.top_overlap.min * 100));
    }
    oefmt::sim::FolderFlightWriter folder(command.output, plan.camera, static_cast<int>(plan.poses.size()),
                                          oefmt::sim::groundTruthHeader(plan));
    std::unique_ptr<oefmt::BagFlightWriter> bag;
    if (!command.bag.empty()) bag = std::make_unique<oefmt::BagFlightWriter>(command.bag, plan.camera, command.bag_options);
    oefmt::tools::ProgressBar progress("rendering", plan.poses.size(), command.quiet ? nullptr : stderr);
    // The written frames' contrast, as the estimator sees it (after sampling, noise and gain).
    double std_sum = 0.0, std_min = HUGE_VAL, std_max = 0.0;
    oefmt::sim::renderFlight(plan, [&](int k, const cv::Mat1b& image, const cv::Mat1b&) {
      cv::Scalar mean, std;
      cv::meanStdDev(image, mean, std);
      std_sum += std[0];
      std_min = std::min(std_min, std[0]);
      std_max = std::max(std_max, std[0]);
      folder.write(image, plan.poses[k], plan.stamps[k]);
      if (bag) bag->write(image, plan.stamps[k]);
      progress.update(static_cast<std::size_t>(k) + 1);
    });
    progress.finish();
    folder.finish();
    if (bag) bag->close();
    const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (!command.quiet) {
      std::printf("wrote       %s (%zu frames)%s%s in %.1f s (%.1f ms per frame)\n", command.output.c_str(),
                  plan.poses.size(), bag ? " and " : "", bag ? command.bag.c_str() : "", seconds,
                  seconds * 1000.0 / plan.poses.size());
      std::printf("grey std    of the written frames: mean %.1f, min %.1f, max %.1f grey levels (noise included)\n",
                  std_sum / plan.poses.size(), std_min, std_max);
    }
    return 0;
  } catch (const oefmt::InputError& e) {
    std::fprintf(stderr, "oefmt_simulate: %s\n", e.what());
    return 2;
  } catch (const std::exception& e) {  // DatasetError, BagError, cv::Exception
    std::fprintf(stderr, "oefmt_simulate: %s\n", e.what());
    return 1;
  }
}
