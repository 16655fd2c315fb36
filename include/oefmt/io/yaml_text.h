// SPDX-License-Identifier: GPL-3.0-or-later
// First checks on YAML text before any parser sees it (parseYaml runs them; they also guard
// anything still handed to OpenCV's reader).
#pragma once

#include <cstddef>
#include <string>

namespace oefmt {

/// Largest YAML text accepted: parameter files are a few kilobytes.
constexpr std::size_t kMaxYamlBytes = std::size_t{1} << 20;
/// Deepest nesting accepted (indentation columns + flow brackets + "- " items on one line).
constexpr int kMaxYamlNesting = 64;

/// Throws InputError, naming `what`, for text no parameter file holds and that OpenCV's YAML
/// reader mishandles instead of refusing: a NUL byte (it can loop forever; files cut short by a
/// power loss are padded with them), more than kMaxYamlBytes, or nesting deeper than
/// kMaxYamlNesting (it recurses once per level without a limit: a stack overflow).
void checkYamlText(const std::string& text, const std::string& what);

}  // namespace oefmt
