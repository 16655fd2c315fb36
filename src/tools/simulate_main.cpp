// SPDX-License-Identifier: GPL-3.0-or-later
// oefmt_simulate: renders a flight of a down-looking camera over a multi-depth textured scene and
// writes it in the authors' dataset layout with ground truth (and optionally as a ROS bag).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "command_line.h"
#include "oefmt/error.h"
#include "oefmt/io/vehicle_data.h"
#include "oefmt/ros/bag_io.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/folder_writer.h"
#include "progress.h"

namespace {

constexpr double kDeg = CV_PI / 180.0;

struct Command {
  oefmt::sim::FlightOptions flight;
  std::string output;
  std::string bag;
  oefmt::BagWriterOptions bag_options;
  int threads = -1;
  bool quiet = false;
  bool imu = false;    // write imu.txt
  bool range = false;  // write range.txt
};

/// LAYER=FILE of --texture into the flight's texture files.
void addTextureFile(oefmt::sim::FlightOptions& f, const std::string& text) {
  const auto equals = text.find('=');
  char* end = nullptr;
  const long layer = equals == std::string::npos ? -1 : std::strtol(text.c_str(), &end, 10);
  if (layer < 0 || layer > 16 || end != text.c_str() + equals || equals + 1 >= text.size()) {
    throw oefmt::InputError("--texture needs LAYER=FILE with LAYER 0 (ground), 1, 2, ...");
  }
  if (f.texture_files.size() <= static_cast<std::size_t>(layer)) f.texture_files.resize(layer + 1);
  f.texture_files[layer] = text.substr(equals + 1);
}

/// S[,S2,...] of --texture-style.
std::vector<oefmt::sim::TextureStyle> textureStyles(const std::string& text) {
  std::vector<oefmt::sim::TextureStyle> styles;
  std::stringstream list(text);
  std::string name;
  while (std::getline(list, name, ',')) {
    try {
      styles.push_back(oefmt::parseEnum(oefmt::sim::kTextureStyleNames, name, "texture style"));
    } catch (const oefmt::InputError& e) {
      throw oefmt::InputError(std::string("--texture-style: ") + e.what());
    }
  }
  if (styles.empty()) throw oefmt::InputError("--texture-style needs a style");
  return styles;
}

/// What a flight's options leave to its track, and the checks that span several options.
void completeTrack(oefmt::sim::FlightOptions& f, bool length_set, bool frames_set, bool overlap_set,
                   bool spin_rate_set, bool profile_set) {
  using oefmt::requireInput;
  using oefmt::sim::TrackShape;
  const TrackShape shape = f.track.shape;
  if (shape == TrackShape::kSpin) {
    requireInput(!length_set, "--length does not apply to --track spin (the camera stays at the origin)");
    requireInput(!overlap_set,
                 "--overlap does not apply to --track spin (the camera does not move): give --altitude "
                 "(default 20 m)");
    requireInput(f.track.climb == 0.0, "--climb does not apply to --track spin");
    requireInput(!profile_set, "--climb-profile does not apply to --track spin");
    requireInput(f.track.heading != oefmt::sim::HeadingMode::kTrack, "--heading track needs a moving track, not spin");
  } else {
    requireInput(!spin_rate_set, "--spin-rate applies to --track spin only");
  }
  requireInput(!(profile_set && f.track.climb_profile == oefmt::sim::ClimbProfile::kRamp && shape != TrackShape::kLine),
               "--climb-profile ramp needs --track line (a loop comes back to its start: hill)");
  if (!length_set) f.track.length = shape == TrackShape::kEight ? 880.0 : shape == TrackShape::kLine ? 200.0 : shape == TrackShape::kSpin ? 0.0 : 491.0;
  if (!frames_set) f.track.frames = shape == TrackShape::kEight ? 300 : shape == TrackShape::kCircle ? 200 : 100;
}

/// Reads the command line into `command`; returns the exit status when the tool is to stop here.
std::optional<int> parse(int argc, char** argv, Command& command) {
  using oefmt::requireInput;
  using oefmt::tools::addChoice;
  using oefmt::tools::addNumber;
  CLI::App app(R"(Renders a flight of a pinhole camera looking straight down at a textured ground plane with raised
block tops at further heights (the last level's terraces inclined; optionally solid blocks with
walls), and writes OUTPUT_DIR in the o-eFMT authors' layout: Images/0001.png..., imageList.txt,
timestamps.txt (seconds), cam_param.yaml, plus groundtruth.tum (t x y z qx qy qz qw; world x
east, y north, z up).
Deterministic for a given seed. Defaults: the paper's circle (491 m, 200 frames, 512x512).)",
               "oefmt_simulate");
  oefmt::tools::setUpTool(app, "exit codes: 0 success, 1 write failure, 2 invalid option");
  oefmt::sim::FlightOptions& f = command.flight;
  // An angle option in degrees, kept in radians.
  const auto addAngle = [&app](const std::string& name, double& radians, const std::string& help) {
    return app.add_option_function<double>(name, [&radians](double degrees) { radians = degrees * kDeg; }, help)
        ->type_name("DEG")
        ->check(oefmt::tools::finite());
  };

  app.add_option("OUTPUT_DIR", command.output, "the flight's folder")->type_name("")->required();

  const std::string track = "track";
  app.add_option_function<std::string>(
         "--track",
         [&f](const std::string& name) {
           f.track.shape = oefmt::parseEnum(oefmt::sim::kTrackShapeNames, name, "track");
         },
         "shape (default circle); spin: no motion, the camera turns on the\nspot at the origin")
      ->type_name(oefmt::tools::shownWords(oefmt::sim::kTrackShapeNames))
      ->group(track);
  const CLI::Option* length =
      addNumber(app, "--length", f.track.length, "M",
                "path length [m] (default circle 491, eight 880, line 200; not spin)")
          ->group(track);
  const CLI::Option* frames =
      app.add_option("--frames", f.track.frames,
                     "frames (default circle 200, eight 300, line 100, spin 100); loops\n"
                     "repeat the first frame at the end")
          ->type_name("N")
          ->group(track);
  addNumber(app, "--altitude", f.track.altitude, "M", "height above the ground [m] (default: from --overlap; spin 20)")
      ->group(track);
  const CLI::Option* overlap =
      addNumber(app, "--overlap", f.overlap, "F",
                "target mean overlap of consecutive frames on the ground (0.78;\nnot spin)")
          ->group(track);
  addNumber(app, "--climb", f.track.climb, "M", "altitude change [m], negative for a descent (default 0; not spin)")
      ->group(track);
  const CLI::Option* profile =
      addChoice(app, "--climb-profile", f.track.climb_profile, oefmt::sim::kClimbProfileNames,
                "how a line changes altitude: ramp = linearly to altitude + climb\n"
                "(default), hill = smoothly to it half-way and back; loops: hill")
          ->group(track);
  const CLI::Option* spin_rate =
      addAngle("--spin-rate", f.track.spin_rate, "yaw change per frame of a spin, either sign (default 6)")
          ->group(track);
  addChoice(app, "--heading", f.track.heading, oefmt::sim::kHeadingModeNames,
            "yaw fixed, or following the direction of motion (default fixed)")
      ->group(track);
  addAngle("--yaw", f.track.yaw, "fixed yaw, or offset to the direction of motion (default 0)")->group(track);
  addAngle("--direction", f.track.line_direction, "direction of a line track, from east counter-clockwise (default 0)")
      ->group(track);

  // Later options override earlier ones (--size 256 --width 320): these run as they are read.
  const std::string camera = "camera";
  app.add_option_function<int>(
         "--size", [&f](int size) { f.width = f.height = size; }, "width and height (default 512)")
      ->type_name("PX")
      ->trigger_on_parse()
      ->group(camera);
  app.add_option("--width", f.width, "image width")->type_name("PX")->trigger_on_parse()->group(camera);
  app.add_option("--height", f.height, "image height")->type_name("PX")->trigger_on_parse()->group(camera);
  addNumber(app, "--fx", f.fx, "PX", "focal length (default: 60 deg horizontal field of view)")->group(camera);
  addNumber(app, "--fy", f.fy, "PX", "focal length (default: fx)")->group(camera);
  addNumber(app, "--cx", f.cx, "PX", "principal point (default: image centre)")->group(camera);
  addNumber(app, "--cy", f.cy, "PX", "principal point (default: image centre)")->group(camera);
  addNumber(app, "--k1", f.distortion.k1, "K",
            "radial distortion rendered and written to cam_param/CameraInfo\n"
            "(a barrel lens sees wider: without --altitude it flies lower)")
      ->group(camera);
  addNumber(app, "--k2", f.distortion.k2, "K", "the same, second coefficient")->group(camera);

  const std::string scene = "scene";
  app.add_option_function<int>(
         "--seed",
         [&f](int seed) {
           requireInput(seed >= 0, "--seed must be >= 0");
           f.seed = static_cast<std::uint32_t>(seed);
         },
         "scene and noise seed (default 1)")
      ->type_name("N")
      ->group(scene);
  oefmt::tools::addNumberList(app, "--levels", f.level_heights, "H1,H2,...",
                              "raised levels' heights [m] (default 0.15, 0.30 and 0.225 of the\naltitude)")
      ->group(scene);
  app.add_flag("--flat", f.flat, "ground plane only, no raised levels")->group(scene);
  addNumber(app, "--incline", f.incline_deg, "DEG", "tilt of the last level's terraces (default 6)")->group(scene);
  addNumber(app, "--raised", f.raised_share, "F", "fraction of the terraces raised, split among the levels (1)")
      ->group(scene);
  addNumber(app, "--fill", f.fill, "F", "probability that a cell of a raised terrace has a top (0.8)")->group(scene);
  addNumber(app, "--cell", f.cell_size, "M",
            "block pitch [m] (default 0.22 of the ground footprint's width at\nthe mean altitude)")
      ->group(scene);
  addNumber(app, "--texel", f.texel, "M",
            "texture resolution [m] (default half a ground pixel at the mean\naltitude)")
      ->group(scene);
  app.add_option("--texture-size", f.texture_size, "procedural texture side [texels] (default 8 x width, <= 4096)")
      ->type_name("N")
      ->group(scene);
  app.add_option_function<std::vector<std::string>>(
         "--texture",
         [&f](const std::vector<std::string>& specs) {
           for (const std::string& spec : specs) addTextureFile(f, spec);
         },
         "image file as texture of a layer (0 ground, 1.. levels); repeatable")
      ->type_name("LAYER=FILE")
      ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll)
      ->group(scene);
  app.add_option_function<std::string>(
         "--texture-style", [&f](const std::string& text) { f.texture_styles = textureStyles(text); },
         "procedural texture per layer, ground first (the last one for the\n"
         "layers beyond the list): mixed (default: ground cells, level 1\n"
         "stripes, level 2 noise, ...), cells, stripes, noise, natural\n"
         "(photo-like, 1/f spectrum), brick, tiles (strictly periodic, about\n"
         "16 bricks or tiles per image width)")
      ->type_name("S[,S2,...]")
      ->group(scene);
  addNumber(app, "--contrast", f.contrast, "STD",
            "rescale every texture to this grey std [grey levels of 255] around\n"
            "mid grey (default: as made); the summary prints the frames' std")
      ->group(scene);
  app.add_flag("--walls", f.walls,
               "solid blocks: tops stand on the ground and their side walls are\n"
               "rendered (default: tops without walls)")
      ->group(scene);

  // --noise and --noise-grey set the same value: the later one counts.
  const std::string sensor = "rendering and sensor";
  app.add_option("--supersample", f.supersample, "N x N rays per pixel (default 2)")->type_name("N")->group(sensor);
  addNumber(app, "--noise", f.sensor.noise, "SIGMA",
            "Gaussian noise std, intensity 0..1 (default 0; 5 grey levels =\n0.0196)")
      ->trigger_on_parse()
      ->group(sensor);
  app.add_option_function<double>(
         "--noise-grey",
         [&f](double grey) {
           f.sensor.noise = grey / 255.0;
           requireInput(f.sensor.noise >= 0.0, "--noise-grey must be >= 0");
         },
         "the same in grey levels of 255 (= --noise SIGMA/255)")
      ->type_name("SIGMA")
      ->check(oefmt::tools::finite())
      ->trigger_on_parse()
      ->group(sensor);
  addNumber(app, "--brightness", f.sensor.brightness, "A", "frame gain 1 + A sin(2 pi k / period) (default 0)")
      ->group(sensor);
  addNumber(app, "--brightness-period", f.sensor.brightness_period, "N", "frames (default 50)")->group(sensor);
  addNumber(app, "--flicker", f.sensor.flicker, "A",
            "random gain per frame, uniform in [1 - A, 1 + A], times the sine's\n(default 0)")
      ->group(sensor);
  app.add_option("--threads", command.threads, "rendering threads (default: all cores)")->type_name("N")->group(sensor);

  const std::string vehicle = "vehicle attitude and sensors";
  app.add_flag("--tilt", f.tilt.follow_acceleration,
               "lean into the horizontal acceleration as a multirotor does\n(atan(a / g)); default level")
      ->group(vehicle);
  addAngle("--wobble", f.tilt.wobble, "amplitude of a smooth random wobble of roll and pitch (default 0)")
      ->group(vehicle);
  addNumber(app, "--wobble-hz", f.tilt.wobble_frequency, "HZ", "the wobble's highest frequency (default 0.5)")
      ->group(vehicle);
  addAngle("--max-tilt", f.tilt.max_tilt, "roll and pitch together are clamped to this (default 25)")->group(vehicle);
  app.add_flag("--imu", command.imu,
               "write imu.txt: orientation, angular velocity and specific force\nat --imu-rate, with noise, gyro bias "
               "and attitude error")
      ->group(vehicle);
  addNumber(app, "--imu-rate", f.imu.rate, "HZ", "IMU samples per second (default 200)")->group(vehicle);
  addAngle("--attitude-error", f.imu.attitude_error, "slow wander of the IMU's roll and pitch (default 0.3)")
      ->group(vehicle);
  app.add_flag("--range", command.range,
               "write range.txt: a downward rangefinder's distance at every frame\n(noise, dropouts as inf)")
      ->group(vehicle);
  addNumber(app, "--range-noise", f.range.noise, "M", "rangefinder noise std (default 0.03)")->group(vehicle);
  addNumber(app, "--range-dropout", f.range.dropout, "P", "probability of a reading without return (default 0.02)")
      ->group(vehicle);

  const std::string output = "time and output";
  addNumber(app, "--rate", f.rate, "HZ", "frame rate (default 5)")->group(output);
  addNumber(app, "--start-time", f.start_time, "S", "stamp of the first frame (default 1.0)")->group(output);
  app.add_option("--bag", command.bag,
                 "also write a ROS bag (sensor_msgs/Image + CameraInfo; with --imu\nand --range also sensor_msgs/Imu on "
                 "/imu/data, sensor_msgs/Range\non /rangefinder/range and their mounts on /tf_static)")
      ->type_name("FILE")
      ->group(output);
  addChoice(app, "--bag-compression", command.bag_options.compression, {"none", "lz4", "bz2"},
            "bag chunk compression (default none)")
      ->group(output);
  app.add_option("--image-topic", command.bag_options.image_topic, "(default /camera/image_raw)")
      ->type_name("T")
      ->group(output);
  app.add_option("--info-topic", command.bag_options.camera_info_topic, "(default /camera/camera_info)")
      ->type_name("T")
      ->group(output);
  app.add_option("--frame-id", command.bag_options.frame_id, "(default camera_optical)")->type_name("F")->group(output);
  app.add_option_function<std::vector<double>>(
         "--imu-mount",
         [&command](const std::vector<double>& rpy) {
           // Rz(yaw) Ry(pitch) Rx(roll): the IMU frame in the body.
           command.bag_options.imu_mount = Eigen::AngleAxisd(rpy[2] * kDeg, Eigen::Vector3d::UnitZ()) *
                                           Eigen::AngleAxisd(rpy[1] * kDeg, Eigen::Vector3d::UnitY()) *
                                           Eigen::AngleAxisd(rpy[0] * kDeg, Eigen::Vector3d::UnitX());
         },
         "the bag's IMU frame turned by roll,pitch,yaw in the body (its messages\nand /tf_static say so; "
         "default 0,0,0)")
      ->type_name("R,P,Y")
      ->expected(3)
      ->delimiter(',')
      ->check(oefmt::tools::finite())
      ->group(output);
  app.add_flag("--quiet", command.quiet, "print nothing but errors")->group(output);

  app.callback([&] {
    const bool given_altitude = app.count("--altitude") > 0;
    requireInput(!given_altitude || f.track.altitude > 0.0, "--altitude must be > 0");
    requireInput(std::fabs(f.track.spin_rate) < CV_PI, "--spin-rate must be in (-180, 180) deg");
    requireInput(app.count("--contrast") == 0 || (f.contrast > 0.0 && f.contrast <= 127.5),
                 "--contrast must be in (0, 127.5] grey levels");
    requireInput(f.sensor.flicker >= 0.0 && f.sensor.flicker < 1.0, "--flicker must be in [0, 1)");
    requireInput(app.count("--threads") == 0 || command.threads >= 1, "--threads must be >= 1");
    completeTrack(f, length->count() > 0, frames->count() > 0, overlap->count() > 0, spin_rate->count() > 0,
                  profile->count() > 0);
  });
  return oefmt::tools::parseCommandLine(app, argc, argv);
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
  if (const std::optional<int> exit_status = parse(argc, argv, command)) return *exit_status;
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
    std::vector<oefmt::RangeSample> ranges;
    oefmt::sim::renderFlight(plan, [&](int k, const cv::Mat1b& image, const cv::Mat1b&) {
      cv::Scalar mean, std;
      cv::meanStdDev(image, mean, std);
      std_sum += std[0];
      std_min = std::min(std_min, std[0]);
      std_max = std::max(std_max, std[0]);
      folder.write(image, plan.poses[k], plan.stamps[k]);
      if (bag) bag->write(image, plan.stamps[k]);
      progress.update(static_cast<std::size_t>(k) + 1);
    }, command.range ? &ranges : nullptr);
    progress.finish();
    folder.finish();
    const std::filesystem::path folder_path(command.output);
    if (command.imu) {
      const std::vector<oefmt::ImuSample> imu = oefmt::sim::simulateFlightImu(plan);
      oefmt::writeImuFile((folder_path / oefmt::kImuFileName).string(), imu,
                          {"oefmt_simulate IMU (frame: base_link, the camera body): t qx qy qz qw wx wy wz ax ay az",
                           "orientation body to world (ENU); angular velocity [rad/s] and specific force [m/s^2] in the body frame"});
      if (bag) {
        for (const oefmt::ImuSample& sample : imu) bag->writeImu(sample);
      }
    }
    if (command.range) {
      oefmt::writeRangeFile((folder_path / oefmt::kRangeFileName).string(), ranges,
                            {"oefmt_simulate rangefinder: t range [m] along the body's -z; inf: no return"});
      if (bag) {
        for (const oefmt::RangeSample& sample : ranges) bag->writeRange(sample);
      }
    }
    if (bag && (command.imu || command.range)) bag->writeMounts(plan.stamps.front());
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
