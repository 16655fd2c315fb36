// SPDX-License-Identifier: GPL-3.0-or-later
// A guard in front of OpenCV's YAML reader (cv::FileStorage), which parameter files and the
// authors' cam_param.yaml go through.
#pragma once

#include <cstddef>
#include <string>

namespace oefmt {

/// Largest YAML text accepted: parameter files are a few kilobytes.
constexpr std::size_t kMaxYamlBytes = std::size_t{1} << 20;
/// Deepest nesting accepted (indentation columns + flow brackets + "- " items on one line).
constexpr int kMaxYamlNesting = 64;

/// Throws InputError, naming `what`, for text that OpenCV's YAML reader mishandles instead of
/// refusing: a NUL byte (it can loop forever; files cut short by a power loss are padded with
/// them), more than kMaxYamlBytes, or nesting deeper than kMaxYamlNesting (it recurses once per
/// level without a limit, and a stack overflow is a crash no handler can catch).
void checkYamlText(const std::string& text, const std::string& what);

}  // namespace oefmt
