// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/io/yaml_text.h"

#include <algorithm>

#include "oefmt/error.h"

namespace oefmt {

void checkYamlText(const std::string& text, const std::string& what) {
  if (text.find('\0') != std::string::npos) throw InputError(what + " is not text (it holds a NUL byte)");
  if (text.size() > kMaxYamlBytes) {
    throw InputError(what + " is " + std::to_string(text.size()) + " bytes: over the " +
                     std::to_string(kMaxYamlBytes) + " bytes a parameter file may have");
  }
  int flow_depth = 0, deepest = 0, line = 1, deepest_line = 1;
  char quote = 0;
  bool comment = false, line_start = true;
  int indent = 0, items = 0;
  for (const char c : text) {
    if (c == '\n') {
      ++line;
      comment = false;
      quote = 0;  // YAML quotes do not span lines in parameter files; do not let one run on
      line_start = true;
      indent = items = 0;
      continue;
    }
    if (comment) continue;
    if (line_start) {
      if (c == ' ') {
        ++indent;
        continue;
      }
      if (c == '-') {
        ++items;  // "- - - x": each dash opens a sequence (the space after it is skipped next)
        continue;
      }
      line_start = false;
    }
    if (quote != 0) {
      if (c == quote) quote = 0;
      continue;
    }
    switch (c) {
      case '#': comment = true; break;
      case '"':
      case '\'': quote = c; break;
      case '[':
      case '{': ++flow_depth; break;
      case ']':
      case '}': flow_depth = std::max(0, flow_depth - 1); break;
      default: break;
    }
    const int nesting = indent + items + flow_depth;
    if (nesting > deepest) {
      deepest = nesting;
      deepest_line = line;
    }
  }
  if (deepest > kMaxYamlNesting) {
    throw InputError(what + " nests " + std::to_string(deepest) + " levels deep at line " +
                     std::to_string(deepest_line) + ": more than the " + std::to_string(kMaxYamlNesting) +
                     " a parameter file may have");
  }
}

}  // namespace oefmt
