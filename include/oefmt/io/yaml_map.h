// SPDX-License-Identifier: GPL-3.0-or-later
// The YAML of parameter files (config/*.yaml, cam_param.yaml, the node's parameters), read
// without OpenCV: cv::FileStorage loops forever on some malformed documents (found by fuzzing,
// e.g. "%YAML:1.0\n e: m\nmd--\n") and recurses without a depth limit. This reader makes one
// pass over the lines and refuses, with the line number, whatever it does not take.
#pragma once

#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace oefmt {

/// A scalar or a map of further nodes (keys in file order).
struct YamlNode {
  int line = 0;          ///< 1-based line of the key (0: the document)
  bool is_map = false;
  bool is_null = false;  ///< "key:" with nothing after it and nothing nested
  std::string scalar;    ///< the value, unquoted, when !is_map
  std::vector<std::pair<std::string, YamlNode>> children;  ///< when is_map

  /// The child named `key`, or nullptr.
  const YamlNode* find(const std::string& key) const;
};

/// A scalar's text as a number: strtod must read all of it (leading blanks aside). nullopt for
/// empty or partly numeric text; `out_of_range` (when given) tells whether strtod reported ERANGE.
std::optional<double> yamlNumber(const std::string& text, bool* out_of_range = nullptr);

/// Parses block maps of scalars: "key: value" lines nested by indentation (spaces), plain or
/// quoted ('...' or "...") keys and values, "#" comments, leading "%" directives and a "---"
/// start marker, a "..." end marker. Refused with an InputError naming `what` and the line:
/// sequences ("- x"), flow collections ([...] and {...}), anchors, aliases, tags, block
/// scalars (| and >), tabs in indentation, duplicate keys, a second document, nesting deeper
/// than 16 maps, and everything checkYamlText refuses.
YamlNode parseYaml(const std::string& text, const std::string& what);

}  // namespace oefmt
