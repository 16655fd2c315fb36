// SPDX-License-Identifier: GPL-3.0-or-later
// oefmt_register_pair: registers two images (or, without arguments, a generated pair with a known
// motion) and prints rotation, zoom, translation, their sigmas and the energy-vector peaks.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <string>


#include "oefmt/error.h"
#include "oefmt/io/image_decoding.h"
#include "oefmt/registration/registration.h"
#include "oefmt/sim/similarity_views.h"
#include "oefmt/sim/texture.h"
#include "oefmt/io/fft_wisdom.h"

namespace {

void usage() {
  std::puts(
      "usage: oefmt_register_pair [--size N] [--classic] [OLDER_IMAGE NEWER_IMAGE]\n"
      "Registers OLDER -> NEWER. Without images, registers a generated textured pair moved by\n"
      "rotation 17 deg, zoom 1.06 and shift (12.5, -7.25) px and compares with that truth.");
}

int argmaxOf(const std::vector<float>& v) {
  int best = 0;
  for (int i = 1; i < static_cast<int>(v.size()); ++i) {
    if (v[i] > v[best]) best = i;
  }
  return best;
}

}  // namespace

int main(int argc, char** argv) {
  oefmt::useDefaultFftWisdom();
  int size = 512;
  oefmt::RegistrationMethod method = oefmt::RegistrationMethod::kEnergyVectors;
  std::vector<std::string> paths;
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--help" || arg == "-h") {
      usage();
      return 0;
    } else if (arg == "--classic") {
      method = oefmt::RegistrationMethod::kClassic;
    } else if (arg == "--size" && i + 1 < argc) {
      size = std::atoi(argv[++i]);
    } else if (!arg.empty() && arg[0] == '-') {
      std::fprintf(stderr, "oefmt_register_pair: unknown option '%s'\n", arg.c_str());
      usage();
      return 2;
    } else {
      paths.push_back(arg);
    }
  }
  if (!paths.empty() && paths.size() != 2) {
    usage();
    return 2;
  }
  try {
    oefmt::RegistrationConfig config;
    config.size = size;
    // One pair does not repay patient planning (seconds): measure, unless the wisdom of an
    // earlier run already holds patient plans of this size.
    if (!oefmt::fftPlansKnown(size, config.fft_planning)) config.fft_planning = oefmt::FftPlanning::kMeasure;
    oefmt::Registrar registrar(config);
    cv::Mat older, newer;
    oefmt::sim::ViewMotion truth;
    truth.rotation = 17.0 * CV_PI / 180.0;
    truth.zoom = 1.06;
    truth.shift = {12.5, -7.25};
    if (paths.empty()) {
      const cv::Mat1f texture = oefmt::sim::proceduralTexture({2048, 2048}, 1);
      older = oefmt::sim::renderView(texture, {1024, 1024}, {}, size);
      newer = oefmt::sim::renderView(texture, {1024, 1024}, truth, size);
      std::printf("generated pair: rotation %.3f deg, zoom %.4f, shift (%.2f, %.2f) px\n",
                  truth.rotation * 180.0 / CV_PI, truth.zoom, truth.shift.x, truth.shift.y);
    } else {
      older = oefmt::readImageFile(paths[0]);
      newer = oefmt::readImageFile(paths[1]);
      for (int k = 0; k < 2; ++k) {
        if ((k == 0 ? older : newer).empty()) {
          std::fprintf(stderr, "oefmt_register_pair: cannot read image '%s'\n", paths[k].c_str());
          return 1;
        }
      }
    }
    const auto start = std::chrono::steady_clock::now();
    const oefmt::FrameSpectra a = registrar.analyse(older);
    const oefmt::FrameSpectra b = registrar.analyse(newer);
    const oefmt::PairRegistration r = registrar.registerPair(a, b, method);
    const double ms =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
    std::printf("status      %s (confidence %.2f)\n", oefmt::toString(r.status), r.confidence);
    std::printf("rotation    %9.4f deg   sigma %.4f deg%s\n", r.rotation * 180.0 / CV_PI,
                r.rotation_sigma * 180.0 / CV_PI, r.half_turn ? "  (half turn resolved)" : "");
    std::printf("zoom        %9.5f       sigma(ln) %.5f\n", r.zoom, r.log_zoom_sigma);
    std::printf("translation (%.3f, %.3f) px  |d| %.3f px  sigma %.3f px\n", r.translation.x,
                r.translation.y, r.shift, r.shift_sigma);
    std::printf("direction   %9.4f deg   sigma %.4f deg\n", r.direction * 180.0 / CV_PI,
                r.direction_sigma * 180.0 / CV_PI);
    if (!r.zoom_energy.empty()) {
      std::printf("energy peaks: zoom bin %d, translation bin %d (%.2f px)\n",
                  argmaxOf(r.zoom_energy), argmaxOf(r.translation_energy),
                  argmaxOf(r.translation_energy) * registrar.shiftPerBin());
    }
    std::printf("time        %.2f ms (both frames analysed + registration, first call)\n", ms);
    if (paths.empty()) {
      const double rotation_error = std::fabs(r.rotation - truth.rotation) * 180.0 / CV_PI;
      const double zoom_error = std::fabs(r.zoom / truth.zoom - 1.0) * 100.0;
      const double shift_error = std::hypot(r.translation.x - truth.shift.x, r.translation.y - truth.shift.y);
      std::printf("error       rotation %.4f deg, zoom %.4f %%, shift %.3f px\n", rotation_error,
                  zoom_error, shift_error);
    }
    return r.usable() ? 0 : 3;
  } catch (const oefmt::InputError& e) {
    std::fprintf(stderr, "oefmt_register_pair: %s\n", e.what());
    return 2;
  }
}
