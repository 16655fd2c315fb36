// SPDX-License-Identifier: GPL-3.0-or-later
// oefmt_offline: runs the estimator over a dataset folder or a bag as fast as the CPU allows and
// writes the trajectory (TUM), optional per-frame diagnostics (CSV) and a summary.
#include <sys/resource.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <deque>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <memory>
#include <numeric>
#include <optional>
#include <string>
#include <vector>

#include "command_line.h"
#include "diagnostics_csv.h"
#include "frame_source.h"
#include "oefmt/error.h"
#include "oefmt/estimation/estimator.h"
#include "oefmt/estimation/estimator_config.h"
#include "oefmt/estimation/range_gate.h"
#include "oefmt/io/config_file.h"
#include "oefmt/registration/image_prep.h"
#include "progress.h"
#include "oefmt/registration/spectra.h"
#include "oefmt/io/tum.h"
#include "oefmt/io/undistortion.h"
#include "oefmt/io/fft_wisdom.h"
#include "oefmt/io/nadir_view.h"
#include "oefmt/io/vehicle_data.h"
#include "oefmt/ros/bag_io.h"
#include "oefmt/ros/vehicle_messages.h"
#include "oefmt/io/run_setup.h"

namespace {

struct Options {
  std::string images, bag, image_topic, camera_info_topic, imu_topic, range_topic, output, diagnostics, config;
  std::optional<oefmt::EstimatorMode> mode;
  double altitude = -1.0;
  double fx = 0.0;
  long max_frames = -1;
  bool undistort = true;
  bool use_imu = true;
  bool use_range = true;
  bool quiet = false;
  bool print_columns = false;
};

/// Reads the command line into `o`; returns the exit status when the tool is to stop here.
std::optional<int> parseArguments(int argc, char** argv, Options& o) {
  CLI::App app(
      "Runs the estimator over a dataset folder (--images) or a ROS bag (--bag) as fast as the CPU\n"
      "allows and writes the trajectory, optional per-frame diagnostics and a summary.",
      "oefmt_offline");
  oefmt::tools::setUpTool(
      app, "Exit status: 0 done, 1 an input could not be read (the trajectory so far is kept), 2 usage.");
  app.add_option("--images", o.images,
                 "a folder in the o-eFMT authors' layout (Images/, imageList.txt,\n"
                 "cam_param.yaml, optional timestamps.txt)")
      ->type_name("DIR");
  app.add_option("--bag", o.bag, "a ROS 1 bag with sensor_msgs/Image or CompressedImage")->type_name("FILE");
  app.add_option("--image-topic", o.image_topic, "image topic in the bag (default: its only image topic)")
      ->type_name("T");
  app.add_option("--camera-info-topic", o.camera_info_topic,
                 "CameraInfo topic (default: <image namespace>/camera_info if present;\n'-' ignores intrinsics)")
      ->type_name("T");
  app.add_option("--imu-topic", o.imu_topic,
                 "sensor_msgs/Imu topic in the bag (the camera's mount in its frame\nfrom the bag's /tf_static): "
                 "levels the frames as a folder's imu.txt does")
      ->type_name("T");
  app.add_option("--range-topic", o.range_topic,
                 "sensor_msgs/Range topic of a downward rangefinder in the bag: the\nscale, as a folder's range.txt")
      ->type_name("T");
  app.add_option("--output", o.output,
                 "trajectory, TUM 't x y z qx qy qz qw' (t: a folder's timestamps.txt\n"
                 "[s], or the frame index without a usable one; a bag's header\n"
                 "stamps [s]); REP-103 world: x right, y up of the first image, z up")
      ->type_name("FILE");
  app.add_option("--diagnostics", o.diagnostics,
                 "one CSV line per frame: registration, matching, optimizer, pose,\n"
                 "timing (doc/diagnostics.md describes every column)")
      ->type_name("FILE");
  app.add_flag("--diagnostics-columns", o.print_columns,
               "print doc/diagnostics.md (the diagnostics file's columns) and stop");
  app.add_option("--config", o.config, "parameters (doc/parameters.md describes every key)")->type_name("FILE");
  app.add_option_function<std::string>(
         "--mode",
         [&o](const std::string& mode) { o.mode = oefmt::parseEnum(oefmt::kEstimatorModeNames, mode, "mode"); },
         "overrides the config's mode")
      ->type_name(oefmt::tools::shownWords(oefmt::kEstimatorModeNames));
  oefmt::tools::addNumber(app, "--altitude", o.altitude, "M",
                          "overrides the config's initial_altitude: the altitude above the\n"
                          "dominant plane at the first frame [m], for metric output\n"
                          "(otherwise units of the initial altitude)");
  oefmt::tools::addNumber(app, "--fx", o.fx, "PX",
                          "focal length of the images [px]: replaces the calibration's\n"
                          "(cam_param.yaml/CameraInfo, else the config's camera_fx)");
  app.add_flag_callback("--no-undistort", [&o] { o.undistort = false; },
                        "take the images as undistorted: ignore the lens distortion of\n"
                        "cam_param.yaml/CameraInfo (rectified images, or renders whose\n"
                        "cam_param.yaml is another camera's, as the o-eFMT authors' circle)");
  app.add_flag_callback("--no-imu", [&o] { o.use_imu = false; },
                        "ignore the folder's imu.txt (by default, when it is there, each\n"
                        "frame is turned into a level camera's view with the IMU's roll\n"
                        "and pitch, and the trajectory carries them)");
  app.add_flag_callback("--no-range", [&o] { o.use_range = false; },
                        "ignore the folder's range.txt (by default, when it is there, its\n"
                        "readings give the initial altitude and keep the scale metric)");
  app.add_option("--max-frames", o.max_frames, "stop after N frames")->type_name("N");
  app.add_flag("--quiet", o.quiet, "no progress bar and no summary table");
  app.callback([&o] {
    if (o.print_columns) return;
    oefmt::requireInput(o.images.empty() != o.bag.empty(), "give exactly one of --images and --bag");
    oefmt::requireInput(!o.output.empty(), "--output is required");
    oefmt::requireInput(o.altitude == -1.0 || o.altitude > 0.0, "--altitude must be > 0");
    oefmt::requireInput(o.fx >= 0.0, "--fx must be > 0");
  });
  return oefmt::tools::parseCommandLine(app, argc, argv);
}

// A deep copy: the estimator warps a frame's grey image in place when it becomes the older one.
oefmt::FrameSpectra cloneSpectra(const oefmt::FrameSpectra& s) {
  oefmt::FrameSpectra copy = s;
  copy.grey = s.grey.clone();
  copy.spectrum = s.spectrum.clone();
  copy.log_polar_spectrum = s.log_polar_spectrum.clone();
  return copy;
}

// How many pairs each frame is registered in as the newer one: 1-2, and 0-2 in oefmt mode.
int pairsPerFrame(oefmt::EstimatorMode mode) { return mode == oefmt::EstimatorMode::kOefmt ? 2 : 1; }

// A reading belongs to a frame within this of its stamp [s].
constexpr double kRangeMatch = 0.02;

// A frame's reading, vertical (oefmt::verticalRange).
std::optional<double> verticalRange(const std::vector<oefmt::RangeSample>& ranges, double stamp,
                                    const std::optional<oefmt::CameraTilt>& tilt) {
  return oefmt::verticalRange(ranges, stamp, kRangeMatch, tilt);
}

// A vehicle sensor's samples: the folder's `file_name` when it is there, else the bag's `topic`
// when one is given; `source` names where they came from (empty: nowhere).
template <typename Sample>
std::vector<Sample> readVehicleData(const Options& o, const char* file_name, const std::string& topic,
                                    std::vector<Sample> (*read_file)(const std::string&),
                                    std::vector<Sample> (*read_topic)(const std::string&, const std::string&),
                                    std::string& source) {
  source.clear();
  if (!o.images.empty() && std::filesystem::exists(o.images + "/" + file_name)) {
    source = o.images + "/" + file_name;
    return read_file(source);
  }
  if (!o.bag.empty() && !topic.empty()) {
    source = topic;
    return read_topic(o.bag, topic);
  }
  return {};
}

// The camera's optical frame in the frame of a bag's IMU messages, from the bag's /tf_static; the
// IMU's frame taken as the camera body (the camera looking down its -z) when the bag does not say.
Eigen::Matrix3d cameraMountInImu(const Options& o, const std::string& imu_topic) {
  const std::string imu_frame = oefmt::firstFrameId(o.bag, imu_topic);
  oefmt::BagImageReader images(o.bag, o.image_topic, "-");
  oefmt::BagFrame first;
  const std::string camera_frame = images.next(first) ? first.frame_id : std::string();
  std::string why;
  const std::optional<Eigen::Quaterniond> mount = oefmt::staticRotation(o.bag, imu_frame, camera_frame, why);
  if (mount) {
    if (!o.quiet && imu_frame != camera_frame) {
      std::fprintf(stderr, "oefmt_offline: camera mount from /tf_static: %s in the IMU's %s\n",
                   camera_frame.c_str(), imu_frame.c_str());
    }
    return mount->toRotationMatrix();
  }
  std::fprintf(stderr,
               "oefmt_offline: warning: no camera mount in the IMU's frame (%s -> %s: %s): the IMU's frame "
               "is taken as the camera body (the camera looking down its -z, image right on its x)\n",
               imu_frame.empty() ? "?" : imu_frame.c_str(), camera_frame.empty() ? "?" : camera_frame.c_str(),
               why.c_str());
  return oefmt::downLookingMount();
}

double percentile(std::vector<double> values, double q) {
  if (values.empty()) return 0.0;
  std::sort(values.begin(), values.end());
  const size_t k = std::min(values.size() - 1, static_cast<size_t>(q * (values.size() - 1) + 0.5));
  return values[k];
}

}  // namespace

int main(int argc, char** argv) {
  oefmt::useDefaultFftWisdom();
  Options options;
  if (const std::optional<int> exit_status = parseArguments(argc, argv, options)) return *exit_status;
  if (options.print_columns) {
    std::fputs(oefmt::diagnosticsMarkdown().c_str(), stdout);
    return 0;
  }
  std::ofstream trajectory, diagnostics;
  long frames = 0, not_tracked = 0, restarts = 0, fallbacks = 0;
  std::vector<double> frame_ms;
  double first_stamp = 0.0, last_stamp = 0.0;
  const auto start = std::chrono::steady_clock::now();
  int status = 0;
  try {
    oefmt::EstimatorConfig config =
        options.config.empty() ? oefmt::EstimatorConfig{} : oefmt::loadConfig(options.config);
    if (options.mode) config.mode = *options.mode;
    config.initial_altitude = oefmt::chooseInitialAltitude(
        options.altitude > 0.0 ? std::optional<double>(options.altitude) : std::nullopt, config.initial_altitude);
    config.validate();

    std::unique_ptr<oefmt::FrameSource> opened =
        options.images.empty()
            ? oefmt::openBag(options.bag, options.image_topic, options.camera_info_topic)
            : oefmt::openFolder(options.images);
    const std::string source_text = opened->describe();
    // Whatever the source tolerated changes the result (without its timestamps.txt a folder's
    // frames are a second apart, which widens the motion model's window): said even with --quiet.
    for (const std::string& warning : opened->warnings()) {
      std::fprintf(stderr, "oefmt_offline: warning: %s\n", warning.c_str());
    }
    const cv::Size image_size = opened->imageSize();
    // The camera of the frames as registered: the calibration mapped to the images' size, the
    // lens distortion undone (the node sets up the same, so both register the same frames).
    std::shared_ptr<const oefmt::Undistorter> undistorter;
    if (!image_size.empty()) {
      oefmt::CameraSources sources;
      sources.calibration = opened->calibration();
      sources.calibration_source = opened->calibrationSource();
      sources.override_fx = options.fx > 0.0 ? options.fx : 0.0;
      sources.override_source = "--fx";
      sources.camera_fx = config.camera_fx;
      sources.undistort = options.undistort;
      if (const auto chosen = oefmt::chooseCamera(sources, image_size)) {
        undistorter = std::make_shared<const oefmt::Undistorter>(chosen->camera, image_size,
                                                                 config.registration.size, chosen->source);
        config.working_fx = undistorter->workingFx();
      }
    }
    // Attitude-aided registration: a folder's imu.txt (of the camera body) or a bag's --imu-topic
    // (the camera's mount in the IMU's frame from the bag's /tf_static) gives each frame's roll
    // and pitch, with which the frame is turned into a level camera's view.
    std::string imu_source;
    const std::vector<oefmt::ImuSample> imu_samples =
        options.use_imu ? readVehicleData(options, oefmt::kImuFileName, options.imu_topic, &oefmt::readImuFile,
                                          &oefmt::readImuTopic, imu_source)
                        : std::vector<oefmt::ImuSample>{};
    if (!options.bag.empty() && !imu_source.empty() && imu_samples.empty()) {
      std::fprintf(stderr, "oefmt_offline: warning: %s has no orientation: the frames are taken as level\n",
                   imu_source.c_str());
    }
    std::shared_ptr<oefmt::AttitudeHistory> attitudes;
    std::shared_ptr<const oefmt::NadirView> nadir;
    Eigen::Matrix3d camera_in_imu = oefmt::downLookingMount();
    std::optional<oefmt::TurnHistory> turns;
    if (!imu_samples.empty()) {
      if (!undistorter) {
        std::fprintf(stderr, "oefmt_offline: warning: %s ignored: no intrinsics to level the frames with\n",
                     imu_source.c_str());
      } else {
        if (!options.bag.empty()) camera_in_imu = cameraMountInImu(options, imu_source);
        attitudes = std::make_shared<oefmt::AttitudeHistory>();
        // The camera body's yaw (the level view keeps it): the camera body is the optical frame
        // with y and z flipped.
        turns.emplace(0.1, camera_in_imu * oefmt::downLookingMount().transpose());
        for (const oefmt::ImuSample& sample : imu_samples) {
          attitudes->add(sample.stamp, sample.orientation);
          turns->add(sample.stamp, sample.orientation, sample.angular_velocity);
        }
        nadir = std::make_shared<const oefmt::NadirView>(undistorter->inputCamera(), image_size,
                                                          config.working_fx, config.registration.size);
        if (!options.quiet) {
          std::fprintf(stderr, "oefmt_offline: attitude from %s: frames levelled with its roll and pitch\n",
                       imu_source.c_str());
        }
      }
    }
    auto unlevelled = std::make_shared<std::atomic<long>>(0);
    // A downward rangefinder (a folder's range.txt or a bag's --range-topic): the initial altitude
    // when none is given, and the altitude above the reference plane all along (oefmt::RangeGate
    // tells those readings from roofs'), which keeps the scale metric.
    std::string range_source;
    const std::vector<oefmt::RangeSample> ranges =
        options.use_range ? readVehicleData(options, oefmt::kRangeFileName, options.range_topic,
                                            &oefmt::readRangeFile, &oefmt::readRangeTopic, range_source)
                          : std::vector<oefmt::RangeSample>{};
    if (!ranges.empty() && !options.quiet) std::fprintf(stderr, "oefmt_offline: altitude from %s\n", range_source.c_str());
    oefmt::RangeAltitude range_altitude;
    // The reader thread decodes each frame and makes its spectra (the frame's FFTs) while this
    // one registers the previous frame. Two frames queued let the reader run ahead over a slow
    // frame (one was slower; a second reader thread gained nothing more and cost memory, see
    // doc/performance.md); each frame queued costs the memory of its spectra.
    if (!options.quiet) {
      const std::string notice = oefmt::fftPlanningNotice(config.registration);
      if (!notice.empty()) std::fprintf(stderr, "oefmt_offline: %s\n", notice.c_str());
    }
    const auto context = std::make_shared<const oefmt::SpectralContext>(config.modeRegistration());
    // While this thread still has a frame queued, the reader also correlates each frame's
    // log-polar spectrum with the frames its pairs will register it against (1-2, and 0-2 in
    // oefmt mode): the registrations' first step, moved off their threads when the reader is
    // ahead of them (doc/performance.md).
    const auto builder = std::make_shared<oefmt::SpectraBuilder>(context);
    builder->setLookback(pairsPerFrame(config.mode));
    oefmt::PrefetchingSource source(
        std::move(opened), 2,
        [builder, undistorter, attitudes, nadir, camera_in_imu, unlevelled](oefmt::SourceFrame& frame) {
          if (attitudes) {
            frame.tilt = oefmt::cameraTiltAt(*attitudes, frame.stamp, camera_in_imu);
            if (frame.tilt) {
              frame.spectra = builder->build(nadir->prepare(frame.image, oefmt::nadirFromOptical(*frame.tilt)));
              return;
            }
            ++*unlevelled;  // no attitude at this stamp: the frame is taken as level
          }
          frame.spectra = builder->build(undistorter ? undistorter->apply(frame.image) : frame.image);
        },
        [builder](oefmt::SourceFrame& frame) { builder->correlateWithRecent(frame.spectra); });

    trajectory.open(options.output);
    if (!trajectory) throw oefmt::InputError("cannot write '" + options.output + "'");
    trajectory << "# oefmt_offline " << oefmt::toString(config.mode) << ": t x y z qx qy qz qw ("
               << (config.initial_altitude > 0.0 || !ranges.empty() ? "metres" : "units of the initial altitude")
               << ")\n";
    if (!options.diagnostics.empty()) {
      diagnostics.open(options.diagnostics);
      if (!diagnostics) throw oefmt::InputError("cannot write '" + options.diagnostics + "'");
      diagnostics << oefmt::diagnosticsCsvHeader();
    }
    if (!options.quiet) {
      std::fprintf(stderr, "oefmt_offline: %s, mode %s\n", source_text.c_str(), oefmt::toString(config.mode));
      if (undistorter) {
        for (const std::string& note : undistorter->notes()) std::fprintf(stderr, "oefmt_offline: %s\n", note.c_str());
      }
    }

    std::unique_ptr<oefmt::Estimator> estimator;
    const size_t total = options.max_frames >= 0
                             ? std::min<size_t>(source.source().size(), options.max_frames)
                             : source.source().size();
    oefmt::tools::ProgressBar progress("oefmt_offline", total, options.quiet ? nullptr : stderr);
    // With a rangefinder and no altitude given, the first frames are run once ahead, in the units
    // of the first reading, to find which of the layers in view the readings saw (rangeScale): the
    // initial altitude is then the reference plane's metric depth.
    std::deque<oefmt::SourceFrame> replay;
    if (!ranges.empty() && !(options.altitude > 0.0)) {
      oefmt::SourceFrame ahead;
      std::unique_ptr<oefmt::Estimator> provisional;
      std::vector<oefmt::RangeObservation> observations;
      while (replay.size() < oefmt::kRangeVoteFrames && source.next(ahead)) {
        const std::optional<double> vertical = verticalRange(ranges, ahead.stamp, ahead.tilt);
        if (!provisional) {
          if (!vertical) break;  // the first frame has no reading: the first reading decides
          oefmt::EstimatorConfig provisional_config = config;
          provisional_config.initial_altitude = *vertical;
          provisional = std::make_unique<oefmt::Estimator>(provisional_config, context);
        }
        oefmt::SourceFrame copy = ahead;
        copy.spectra = cloneSpectra(ahead.spectra);
        replay.push_back(std::move(ahead));
        const std::optional<oefmt::Estimate> e = provisional->push(std::move(copy.spectra), copy.stamp);
        if (!e || !vertical) continue;
        const cv::Point2d beam = oefmt::beamInFrame(copy.tilt, provisional->config().working_fx);
        observations.push_back(oefmt::rangeObservation(*provisional, *e, *vertical, beam));
      }
      if (provisional) {
        const double first = provisional->config().initial_altitude;
        if (const std::optional<double> factor = oefmt::rangeScale(observations)) {
          config.initial_altitude = *factor * first;
        } else {
          config.initial_altitude = first;
        }
      }
    }
    oefmt::SourceFrame frame;
    const auto nextFrame = [&]() {
      if (replay.empty()) return source.next(frame);
      frame = std::move(replay.front());
      replay.pop_front();
      return true;
    };
    while ((options.max_frames < 0 || frames < options.max_frames) && nextFrame()) {
      if (!estimator) {
        if (!undistorter && !options.quiet) {
          std::fprintf(stderr, "oefmt_offline: no intrinsics (no cam_param.yaml/CameraInfo, no "
                               "--fx, no camera_fx): assuming a 53 degree field of view\n");
        }
        if (!ranges.empty() && !(config.initial_altitude > 0.0)) {
          const std::optional<double> first = verticalRange(ranges, frame.stamp, frame.tilt);
          if (first) config.initial_altitude = *first;
        }
        estimator = std::make_unique<oefmt::Estimator>(config, context);
        const std::string upscaling = oefmt::upscalingWarning(frame.image_size, config.registration.size);
        if (!upscaling.empty()) std::fprintf(stderr, "oefmt_offline: warning: %s\n", upscaling.c_str());
        first_stamp = frame.stamp;
      }
      // The gyro's turn since the previous frame: the rotation the registration searches around.
      if (turns && estimator->frameCount() > 0) {
        if (const std::optional<double> turn = turns->turn(last_stamp, frame.stamp)) {
          estimator->setTurn(*turn, oefmt::kGyroRateError * (frame.stamp - last_stamp));
        }
      }
      if (frame.tilt) estimator->setLevelled();
      std::optional<oefmt::Estimate> estimate;
      try {
        estimate = estimator->push(std::move(frame.spectra), frame.stamp);
      } catch (const oefmt::InputError& e) {
        throw oefmt::InputError(frame.name + ": " + e.what());  // which frame, for the user
      }
      ++frames;
      if (!estimate) {
        ++not_tracked;
        std::fprintf(stderr, "oefmt_offline: %s skipped: its stamp %.9f is not after the previous one\n",
                     frame.name.c_str(), frame.stamp);
        continue;
      }
      last_stamp = frame.stamp;
      frame_ms.push_back(estimate->total_ms);
      if (estimate->state != oefmt::TrackingState::kTracking &&
          estimate->state != oefmt::TrackingState::kStarted) {
        ++not_tracked;
      }
      if (estimate->state == oefmt::TrackingState::kRestarted) ++restarts;
      if (estimate->loop.status == oefmt::OptimizerStatus::kFallback) ++fallbacks;
      if (!ranges.empty() && config.initial_altitude > 0.0 &&
          range_altitude.update(*estimator, *estimate, verticalRange(ranges, frame.stamp, frame.tilt),
                                oefmt::beamInFrame(frame.tilt, estimator->config().working_fx))) {
        estimate->pose = estimator->pose();
      }
      trajectory << (frame.tilt ? oefmt::toTumLine(estimate->pose, *frame.tilt) : oefmt::toTumLine(estimate->pose))
                 << '\n';
      if (diagnostics.is_open()) diagnostics << oefmt::diagnosticsCsvLine(*estimate);
      progress.update(static_cast<size_t>(frames));
    }
    progress.finish();
    if (!options.quiet) {
      if (!ranges.empty()) {
        std::fprintf(stderr, "oefmt_offline: scale from the rangefinder (%ld readings taken, %ld refused)\n",
                     range_altitude.gate().accepted(), range_altitude.gate().refused());
      } else if (config.initial_altitude > 0.0) {
        std::fprintf(stderr, "oefmt_offline: scale from the initial altitude (%g m), kept by the images\n",
                     config.initial_altitude);
      } else {
        std::fprintf(stderr, "oefmt_offline: no metric scale: units of the initial altitude\n");
      }
    }
    if (*unlevelled > 0) {
      std::fprintf(stderr,
                   "oefmt_offline: warning: %ld frames had no IMU attitude within 0.1 s of their stamp and were "
                   "taken as level\n",
                   unlevelled->load());
    }
  } catch (const std::exception& e) {
    // Keep and close what was written so far: a partial trajectory is still a valid file.
    std::fprintf(stderr, "oefmt_offline: error: %s\n", e.what());
    status = 1;
  }
  trajectory.flush();
  diagnostics.flush();
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!options.quiet) {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    const double data_s = last_stamp - first_stamp;
    std::fprintf(stderr,
                 "frames %ld | not tracked %ld | restarts %ld | optimizer fallbacks %ld\n"
                 "estimator ms/frame: mean %.2f, median %.2f, p95 %.2f | wall %.2f s = %.2f ms/frame"
                 " | peak memory %.1f MB",
                 frames, not_tracked, restarts, fallbacks,
                 frame_ms.empty() ? 0.0 : std::accumulate(frame_ms.begin(), frame_ms.end(), 0.0) / frame_ms.size(),
                 percentile(frame_ms, 0.5), percentile(frame_ms, 0.95), wall_s,
                 frames > 0 ? wall_s * 1e3 / frames : 0.0, usage.ru_maxrss / 1024.0);
    if (!options.bag.empty() && data_s > 0.0) std::fprintf(stderr, " | real-time factor %.1fx", data_s / wall_s);
    std::fprintf(stderr, "\n");
  }
  return status;
}
