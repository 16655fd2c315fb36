// SPDX-License-Identifier: GPL-3.0-or-later
// The median and the median absolute deviation's Gaussian sigma, shared by the robust fits of the
// registration (image blocks) and the estimation (rates, tilt, deviations).
#pragma once

#include <algorithm>
#include <cstddef>
#include <vector>

namespace oefmt {

/// A Gaussian's sigma per median absolute deviation.
inline constexpr double kMadToSigma = 1.4826;

/// The middle value (the upper middle of an even count); `values` must not be empty.
inline double medianOf(std::vector<double> values) {
  const auto middle = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), middle, values.end());
  return *middle;
}

}  // namespace oefmt
