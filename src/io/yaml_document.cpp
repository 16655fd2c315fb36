// SPDX-License-Identifier: GPL-3.0-or-later
#include "yaml_document.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <set>
#include <vector>

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
      quote = 0;  // quotes do not span lines in parameter files; do not let one run on
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

int yamlLine(const YAML::Node& node) {
  const int line = node.Mark().line;
  return line >= 0 ? line + 1 : 0;
}

std::string yamlWhere(const std::string& what, const YAML::Node& node) {
  const int line = yamlLine(node);
  return line > 0 ? what + ", line " + std::to_string(line) : what;
}

void requireUniqueKeys(const YAML::Node& map, const std::string& what) {
  std::set<std::string> seen;
  for (const auto& entry : map) {
    const YAML::Node& key = entry.first;
    if (!key.IsScalar()) throw InputError(yamlWhere(what, key) + ": a key that is not a plain word");
    if (!seen.insert(key.Scalar()).second) {
      throw InputError(yamlWhere(what, key) + ": the key '" + key.Scalar() + "' appears twice");
    }
  }
}

YAML::Node parseYamlMap(const std::string& text, const std::string& what) {
  checkYamlText(text, what);
  std::vector<YAML::Node> documents;
  try {
    documents = YAML::LoadAll(text);
  } catch (const YAML::Exception& e) {
    const std::string where = e.mark.is_null() ? what : what + ", line " + std::to_string(e.mark.line + 1);
    throw InputError(where + ": " + e.msg);
  }
  if (documents.size() > 1) {
    throw InputError(yamlWhere(what, documents[1]) + ": a second document: one map of parameters per file");
  }
  if (documents.empty() || documents[0].IsNull()) return YAML::Node(YAML::NodeType::Map);
  const YAML::Node& root = documents[0];
  if (!root.IsMap()) throw InputError(yamlWhere(what, root) + ": expected a map of 'key: value' lines");
  requireUniqueKeys(root, what);
  return root;
}

bool yamlNumber(const std::string& text, double& value, bool* out_of_range) {
  if (text.empty()) return false;
  char* end = nullptr;
  errno = 0;
  value = std::strtod(text.c_str(), &end);
  if (out_of_range != nullptr) *out_of_range = errno == ERANGE;
  return end == text.c_str() + text.size();
}

}  // namespace oefmt
