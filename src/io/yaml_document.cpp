// SPDX-License-Identifier: GPL-3.0-or-later
#include "yaml_document.h"

#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <set>
#include <sstream>

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

namespace {

// What one document holds, from yaml-cpp's parser events: the count of nodes other than null
// and where the first one is.
class ContentCounter : public YAML::EventHandler {
 public:
  int content = 0;
  YAML::Mark first = YAML::Mark::null_mark();

  void OnDocumentStart(const YAML::Mark&) override {}
  void OnDocumentEnd() override {}
  void OnNull(const YAML::Mark&, YAML::anchor_t) override {}
  void OnAlias(const YAML::Mark& mark, YAML::anchor_t) override { count(mark); }
  void OnScalar(const YAML::Mark& mark, const std::string&, YAML::anchor_t, const std::string&) override {
    count(mark);
  }
  void OnSequenceStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t,
                       YAML::EmitterStyle::value) override {
    count(mark);
  }
  void OnSequenceEnd() override {}
  void OnMapStart(const YAML::Mark& mark, const std::string&, YAML::anchor_t, YAML::EmitterStyle::value) override {
    count(mark);
  }
  void OnMapEnd() override {}

 private:
  void count(const YAML::Mark& mark) {
    if (content++ == 0) first = mark;
  }
};

// True when some line holds more than blanks, a comment, a directive or a document marker.
bool hasContent(const std::string& text) {
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    const auto start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#' || (start == 0 && line[0] == '%')) continue;
    const std::string body = line.substr(start, line.find_last_not_of(" \t\r") + 1 - start);
    if (start == 0 && (body == "---" || body == "...")) continue;
    return true;
  }
  return false;
}

std::string atLine(const std::string& what, const YAML::Mark& mark) {
  return mark.is_null() ? what : what + ", line " + std::to_string(mark.line + 1);
}

}  // namespace

YAML::Node parseYamlMap(const std::string& text, const std::string& what) {
  checkYamlText(text, what);
  YAML::Node root;
  try {
    // Documents are counted by the parser, three at most, and only the first is built (Load):
    // on some malformed text (a stray ',') yaml-cpp 0.7's parser reports one more empty
    // document for ever, so that LoadAll never returns.
    std::istringstream stream(text);
    YAML::Parser parser(stream);
    for (int document = 0; document < 3; ++document) {
      ContentCounter counter;
      if (!parser.HandleNextDocument(counter)) break;
      if (document > 0 && counter.content > 0) {
        throw InputError(atLine(what, counter.first) + ": a second document: one map of parameters per file");
      }
      if (document == 2) throw InputError(what + ": not YAML the reader can end (a stray ',' or '&'?)");
    }
    root = YAML::Load(text);
  } catch (const YAML::Exception& e) {
    throw InputError(atLine(what, e.mark) + ": " + e.msg);
  }
  if (root.IsNull()) {
    // An empty document (comments only) is an empty map; yaml-cpp also reads some malformed
    // text (an anchor before an open quote) as null, which must not pass as "no parameters".
    if (hasContent(text)) throw InputError(what + ": holds no map of 'key: value' lines that the YAML reader can read");
    return YAML::Node(YAML::NodeType::Map);
  }
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
