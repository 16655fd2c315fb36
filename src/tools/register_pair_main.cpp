// SPDX-License-Identifier: GPL-3.0-or-later
// oefmt_register_pair: registers two images (or, without arguments, a generated pair with a known
// motion) and prints rotation, zoom, translation, their sigmas and the energy-vector peaks.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <optional>
#include <string>
#include <vector>

#include "command_line.h"
#include "oefmt/error.h"
#include "oefmt/io/image_decoding.h"
#include "oefmt/registration/registration.h"
#include "oefmt/sim/similarity_views.h"
#include "oefmt/sim/texture.h"
#include "oefmt/io/fft_wisdom.h"

namespace {

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
  std::string older_path, newer_path;
  CLI::App app(
      "Registers OLDER -> NEWER. Without images, registers a generated textured pair moved by\n"
      "rotation 17 deg, zoom 1.06 and shift (12.5, -7.25) px and compares with that truth.",
      "oefmt_register_pair");
  oefmt::tools::setUpTool(app, "exit codes: 0 registered, 1 unreadable image, 2 invalid option, 3 registration failed");
  app.add_option("--size", size, "working image size (default 512)")->type_name("N");
  app.add_flag_callback("--classic", [&method] { method = oefmt::RegistrationMethod::kClassic; },
                        "the classic Fourier-Mellin registration (single peaks, no energy vectors)");
  app.add_option("OLDER_IMAGE", older_path, "the earlier image")->type_name("");
  app.add_option("NEWER_IMAGE", newer_path, "the later image")->type_name("");
  app.callback([&] { oefmt::requireInput(older_path.empty() == newer_path.empty(), "give two images or none"); });
  if (const std::optional<int> exit_status = oefmt::tools::parseCommandLine(app, argc, argv)) return *exit_status;
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
    if (older_path.empty()) {
      const cv::Mat1f texture = oefmt::sim::proceduralTexture({2048, 2048}, 1);
      older = oefmt::sim::renderView(texture, {1024, 1024}, {}, size);
      newer = oefmt::sim::renderView(texture, {1024, 1024}, truth, size);
      std::printf("generated pair: rotation %.3f deg, zoom %.4f, shift (%.2f, %.2f) px\n",
                  truth.rotation * 180.0 / CV_PI, truth.zoom, truth.shift.x, truth.shift.y);
    } else {
      try {
        older = oefmt::readImageFile(older_path);
        newer = oefmt::readImageFile(newer_path);
      } catch (const oefmt::InputError& e) {  // names the file
        std::fprintf(stderr, "oefmt_register_pair: %s\n", e.what());
        return 1;
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
    if (older_path.empty()) {
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
