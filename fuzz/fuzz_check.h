// SPDX-License-Identifier: GPL-3.0-or-later
// Contract checks shared by the fuzz targets: a violated check aborts, which libFuzzer records
// as a crash together with the input that caused it.
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include <opencv2/core.hpp>

#include "oefmt/registration/registration.h"

namespace oefmt_fuzz {

// Working size of the targets that register images: small, so that a run tries many inputs.
constexpr int kSize = 64;

// One registrar per process (ESTIMATE plans: no FFTW timing inside a fuzzing run).
inline oefmt::Registrar& registrar() {
  static oefmt::Registrar instance([] {
    oefmt::RegistrationConfig config;
    config.size = kSize;
    config.fft_planning = oefmt::FftPlanning::kEstimate;
    return config;
  }());
  return instance;
}

[[noreturn]] inline void fail(const char* what, double value) {
  std::fprintf(stderr, "CONTRACT VIOLATION: %s (value %g)\n", what, value);
  std::abort();
}

inline void check(bool ok, const char* what, double value = 0.0) {
  if (!ok) fail(what, value);
}

inline void checkFinite(double value, const char* what) { check(std::isfinite(value), what, value); }

// Every element of a float matrix (any channel count) is finite. (Not cv::checkRange: its
// default range excludes FLT_MAX itself, a finite value a float camera image may hold.)
inline void checkFinite(const cv::Mat& m, const char* what) {
  if (m.empty()) return;
  check(m.depth() == CV_32F, what, m.depth());
  const int values_per_row = m.cols * m.channels();
  for (int r = 0; r < m.rows; ++r) {
    const float* row = m.ptr<float>(r);
    for (int i = 0; i < values_per_row; ++i) checkFinite(row[i], what);
  }
}

}  // namespace oefmt_fuzz
