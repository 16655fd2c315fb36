// SPDX-License-Identifier: GPL-3.0-or-later
// Arbitrary bytes as a file -> readCameraParameters (a dataset's cam_param.yaml), the frames'
// undistortion set up from what it accepted, and loadConfig (the configuration file). Both read
// through yaml-cpp. Each must either return checked values or throw its documented exception
// (DatasetError / InputError); anything else escaping (YAML::Exception, bad_alloc, ...)
// terminates the run and is a finding. An accepted configuration must survive a round trip
// through configToYaml. The corpus keeps the documents on which OpenCV's YAML reader, used
// before, never returned; scripts/hardening.sh runs this target in fork mode and replays any
// timeout.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <string>

#include "fuzz_check.h"
#include "oefmt/io/dataset.h"
#include "oefmt/error.h"
#include "oefmt/estimation/estimator_config.h"
#include "oefmt/io/config_file.h"
#include "oefmt/io/undistortion.h"

namespace {

// One scratch file per process (parallel fuzzing jobs must not share it).
std::string scratchPath(const char* suffix) {
  const char* dir = std::getenv("TMPDIR");
  return std::string(dir != nullptr && *dir != '\0' ? dir : "/tmp") + "/oefmt_fuzz_" +
         std::to_string(getpid()) + suffix;
}

void writeFile(const std::string& path, const char* data, size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(data, static_cast<std::streamsize>(size));
  oefmt_fuzz::check(static_cast<bool>(out), "scratch file written");
}

void fuzzCameraParameters(const std::string& path) {
  using namespace oefmt_fuzz;
  try {
    const oefmt::CameraParameters camera = oefmt::readCameraParameters(path);
    const oefmt::Intrinsics& k = camera.intrinsics;
    for (double v : {k.fx, k.fy, k.cx, k.cy}) checkFinite(v, "intrinsic finite");
    check(k.fx > 0.0 && k.fy > 0.0, "fx and fy > 0", k.fx);
    check(k.width >= 0 && k.height >= 0, "width and height >= 0", k.width);
    const oefmt::Distortion& d = camera.distortion;
    for (double v : {d.k1, d.k2, d.p1, d.p2, d.k3, d.k4, d.k5, d.k6}) checkFinite(v, "distortion finite");
    // Any accepted calibration, on small frames (a set-up costs its search): a working frame of
    // finite values from inside the frame, or InputError.
    const cv::Size size(k.width > 0 && k.width <= 96 ? k.width : 80, k.height > 0 && k.height <= 96 ? k.height : 60);
    const oefmt::Undistorter undistorter(camera, size, 64, "cam_param.yaml");
    const cv::Mat out = undistorter.apply(cv::Mat1b(size, 128));
    check(out.cols > 0 && out.rows > 0, "a working frame");
    double low = 0.0, high = 0.0;
    cv::minMaxLoc(out.reshape(1), &low, &high);
    const double expected = undistorter.remaps() ? 128.0 / 255.0 : 128.0;  // grey float, or as given
    check(std::fabs(low - expected) < 1e-4 && std::fabs(high - expected) < 1e-4, "uniform stays uniform", low);
    checkFinite(undistorter.workingFx(), "working fx finite");
  } catch (const oefmt::DatasetError&) {
  } catch (const oefmt::InputError&) {
  }
}

void fuzzConfig(const std::string& path, const std::string& round_trip_path) {
  oefmt::EstimatorConfig config;
  try {
    config = oefmt::loadConfig(path);
  } catch (const oefmt::InputError&) {
    return;
  }
  // Accepted means valid; and the text it writes must load back to the same text.
  config.validate();
  const std::string text = oefmt::configToYaml(config);
  writeFile(round_trip_path, text.data(), text.size());
  const std::string again = oefmt::configToYaml(oefmt::loadConfig(round_trip_path));
  oefmt_fuzz::check(again == text, "configToYaml round trip");
}

// The scratch files, removed when libFuzzer exits normally (kept after a crash).
struct ScratchFiles {
  const std::string input = scratchPath(".yaml");
  const std::string round_trip = scratchPath("_round_trip.yaml");
  ~ScratchFiles() {
    std::remove(input.c_str());
    std::remove(round_trip.c_str());
  }
};

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  static const ScratchFiles files;
  writeFile(files.input, reinterpret_cast<const char*>(data), size);
  fuzzCameraParameters(files.input);
  fuzzConfig(files.input, files.round_trip);
  return 0;
}
