// SPDX-License-Identifier: GPL-3.0-or-later
// Arbitrary bytes as two 64 x 64 float frames -> Registrar::registerPair with both methods. Every
// numeric output must be finite and in its documented range, whatever the pixels (NaN, inf,
// constant, noise). A mode byte picks how the frames are made: 8-bit intensities, raw float bit
// patterns, or the second frame as a fuzzed rotation/zoom/shift of the first (so that the
// confident branches of the registration are reached too).
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include <fuzzer/FuzzedDataProvider.h>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "fuzz_check.h"
#include "oefmt/registration/registration.h"

namespace {

using oefmt_fuzz::kSize;
using oefmt_fuzz::registrar;

// Fills a frame by cycling through bytes: as intensities (k = 1) or float bit patterns (k = 4).
cv::Mat1f frameFrom(const std::vector<uint8_t>& bytes, bool raw_floats) {
  cv::Mat1f frame(kSize, kSize, 0.0f);
  if (bytes.empty()) return frame;
  size_t k = 0;
  for (float& pixel : frame) {
    if (raw_floats) {
      uint8_t word[4];
      for (uint8_t& b : word) b = bytes[k++ % bytes.size()];
      std::memcpy(&pixel, word, sizeof(pixel));
    } else {
      pixel = bytes[k++ % bytes.size()] / 255.0f;
    }
  }
  return frame;
}

void checkRegistration(const oefmt::PairRegistration& r, double min_confidence) {
  using namespace oefmt_fuzz;
  checkFinite(r.rotation, "rotation finite");
  check(std::fabs(r.rotation) <= CV_PI + 1e-9, "rotation within pi", r.rotation);
  checkFinite(r.zoom, "zoom finite");
  check(r.zoom > 0.0, "zoom > 0", r.zoom);
  checkFinite(r.translation.x, "translation x finite");
  checkFinite(r.translation.y, "translation y finite");
  checkFinite(r.direction, "direction finite");
  checkFinite(r.shift, "shift finite");
  check(r.shift >= 0.0, "shift >= 0", r.shift);
  for (double sigma : {r.rotation_sigma, r.log_zoom_sigma, r.direction_sigma, r.shift_sigma}) {
    checkFinite(sigma, "sigma finite");
    check(sigma >= 0.0, "sigma >= 0", sigma);
  }
  checkFinite(r.rotation_zoom_peak, "rotation/zoom peak finite");
  checkFinite(r.translation_peak, "translation peak finite");
  checkFinite(r.confidence, "confidence finite");
  checkFinite(r.peak_confidence, "peak confidence finite");
  checkFinite(r.rival_ratio, "rival ratio finite");
  check(r.peak_confidence >= 0.0 && r.peak_confidence <= 1.0, "peak confidence in [0, 1]", r.peak_confidence);
  check(r.confidence >= 0.0 && r.confidence <= r.peak_confidence, "confidence in [0, peak confidence]",
        r.confidence);
  check(r.rival_ratio >= 0.0, "rival ratio not negative", r.rival_ratio);
  check(!r.usable() || r.peak_confidence >= min_confidence, "usable implies min peak confidence",
        r.peak_confidence);
  for (float v : r.zoom_energy) checkFinite(v, "zoom energy finite");
  for (float v : r.translation_energy) checkFinite(v, "translation energy finite");
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  cv::setNumThreads(0);  // reproducible runs
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  FuzzedDataProvider input(data, size);
  const uint8_t mode = input.ConsumeIntegralInRange<uint8_t>(0, 2);
  cv::Mat1f older, newer;
  if (mode == 2) {
    const double angle = input.ConsumeIntegralInRange(-180, 180);
    const double zoom = 0.7 + 0.01 * input.ConsumeIntegralInRange(0, 80);
    const double dx = input.ConsumeIntegralInRange(-20, 20);
    const double dy = input.ConsumeIntegralInRange(-20, 20);
    older = frameFrom(input.ConsumeRemainingBytes<uint8_t>(), false);
    cv::Mat transform = cv::getRotationMatrix2D(cv::Point2f(kSize / 2.0f, kSize / 2.0f), angle, zoom);
    transform.at<double>(0, 2) += dx;
    transform.at<double>(1, 2) += dy;
    cv::warpAffine(older, newer, transform, older.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  } else {
    const size_t half = input.remaining_bytes() / 2;
    older = frameFrom(input.ConsumeBytes<uint8_t>(half), mode == 1);
    newer = frameFrom(input.ConsumeRemainingBytes<uint8_t>(), mode == 1);
  }

  oefmt::Registrar& r = registrar();
  // analyse() copies what it keeps, so the spectra outlive nothing they point into.
  const oefmt::FrameSpectra a = r.analyse(older);
  const oefmt::FrameSpectra b = r.analyse(newer);
  const double min_confidence = r.context().config().min_confidence;
  oefmt::RegistrationSurfaces surfaces;
  checkRegistration(r.registerPair(a, b, oefmt::RegistrationMethod::kEnergyVectors, &surfaces),
                    min_confidence);
  checkRegistration(r.registerPair(a, b, oefmt::RegistrationMethod::kClassic), min_confidence);
  return 0;
}
