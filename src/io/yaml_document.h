// SPDX-License-Identifier: GPL-3.0-or-later
// The YAML files oefmt reads (the configuration file, cam_param.yaml), parsed by yaml-cpp with
// the checks those files need on top: one document, a map at the top, no key twice, and a
// bounded input (size, NUL bytes, nesting) before the parser sees it. Errors name the file and
// the line. Private to the I/O code.
#pragma once

#include <cstddef>
#include <string>

#include <yaml-cpp/eventhandler.h>
#include <yaml-cpp/yaml.h>

namespace oefmt {

/// Largest YAML text accepted: parameter files are a few kilobytes.
constexpr std::size_t kMaxYamlBytes = std::size_t{1} << 20;
/// Deepest nesting accepted (indentation columns + flow brackets + "- " items on one line).
constexpr int kMaxYamlNesting = 64;

/// Throws InputError, naming `what`, for text no parameter file holds, before a parser sees it:
/// a NUL byte (files cut short by a power loss are padded with them), more than kMaxYamlBytes,
/// or nesting deeper than kMaxYamlNesting (a recursive parser's stack grows with it).
void checkYamlText(const std::string& text, const std::string& what);

/// The one document of `text`: a map (an empty document gives an empty map). Throws InputError
/// naming `what` ("configuration file 'x.yaml'") and the line for: what checkYamlText refuses,
/// a syntax error, a second document, a top level that is not a map, a key that is not a
/// scalar or that appears twice in the top-level map.
YAML::Node parseYamlMap(const std::string& text, const std::string& what);

/// Throws InputError naming `what` and the line when a key of `map` is not a scalar or appears
/// twice (yaml-cpp keeps both).
void requireUniqueKeys(const YAML::Node& map, const std::string& what);

/// 1-based line of a node in its file (0 when yaml-cpp gives none).
int yamlLine(const YAML::Node& node);

/// "<what>, line <n>" (just `what` without a line).
std::string yamlWhere(const std::string& what, const YAML::Node& node);

/// A scalar's text as a number: strtod must read all of it (leading blanks aside). False for
/// empty or partly numeric text; `out_of_range` (when given) tells whether strtod reported
/// ERANGE (the value is then +-inf, or 0 or a subnormal).
bool yamlNumber(const std::string& text, double& value, bool* out_of_range = nullptr);

}  // namespace oefmt
