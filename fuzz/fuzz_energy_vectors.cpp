// SPDX-License-Identifier: GPL-3.0-or-later
// Arbitrary bytes as two energy vectors (any float, lengths 0..600) -> the stretch (PMT) and
// shift (PMS) matchers with default options, and the peak helpers. The header's contract:
// value always finite, sigma finite and > 0, a valid shift within the search range.
#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

#include <fuzzer/FuzzedDataProvider.h>

#include "fuzz_check.h"
#include "oefmt/registration/pattern_matching.h"

namespace {

// A mode byte picks raw float bit patterns (NaN, inf, negative, denormal) or byte intensities,
// which look more like real energy vectors and reach the matchers' valid branches.
std::vector<float> vectorFrom(FuzzedDataProvider& input, size_t length, bool raw_floats) {
  std::vector<float> v(length, 0.0f);
  for (float& x : v) {
    if (input.remaining_bytes() == 0) break;
    if (raw_floats) {
      const uint32_t bits = input.ConsumeIntegral<uint32_t>();
      std::memcpy(&x, &bits, sizeof(x));
    } else {
      x = input.ConsumeIntegral<uint8_t>() / 16.0f;
    }
  }
  return v;
}

void checkMatch(const oefmt::MatchResult& m) {
  using namespace oefmt_fuzz;
  checkFinite(m.value, "match value finite");
  checkFinite(m.sigma, "match sigma finite");
  check(m.sigma > 0.0, "match sigma > 0", m.sigma);
  if (m.valid) {
    checkFinite(m.error, "valid match error finite");
    checkFinite(m.quality, "valid match quality finite");
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace oefmt_fuzz;
  FuzzedDataProvider input(data, size);
  const bool raw_floats = input.ConsumeBool();
  const size_t length_a = input.ConsumeIntegralInRange<size_t>(0, 600);
  // Mostly equal lengths, as the estimator passes them; sometimes not (must be refused cleanly).
  const size_t length_b = input.ConsumeBool() ? length_a : input.ConsumeIntegralInRange<size_t>(0, 600);
  const std::vector<float> a = vectorFrom(input, length_a, raw_floats);
  const std::vector<float> b = vectorFrom(input, length_b, raw_floats);

  const oefmt::StretchMatchOptions stretch;
  const oefmt::MatchResult pmt = oefmt::matchStretch(a, b, stretch);
  checkMatch(pmt);
  check(pmt.value > 0.0, "stretch factor > 0", pmt.value);

  const oefmt::ShiftMatchOptions shift;
  const oefmt::MatchResult pms = oefmt::matchShift(a, b, shift);
  checkMatch(pms);
  check(!pms.valid || std::fabs(pms.value) <= shift.max_shift, "valid shift within range", pms.value);

  // Peak helpers on the same vector, near a bin the estimator could ask for.
  const double argmax = oefmt::refinedArgmax(a);
  checkFinite(argmax, "refined argmax finite");
  check(a.empty() || (argmax >= -0.5 && argmax <= a.size() - 0.5), "argmax within the vector", argmax);
  const double bin = argmax * 1.5, tolerance = 0.15 * bin + 1.0;
  if (const auto peak = oefmt::peakNear(a, bin, tolerance, 0.01)) {
    checkFinite(*peak, "peak finite");
    check(std::fabs(*peak - bin) <= tolerance, "peak within tolerance", *peak);
  }
  return 0;
}
