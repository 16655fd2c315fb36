// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/io/yaml_map.h"

#include <cerrno>
#include <cstddef>
#include <cstdlib>

#include "oefmt/error.h"
#include "oefmt/io/yaml_text.h"

namespace oefmt {
namespace {

constexpr int kMaxMapDepth = 16;

// One content line: its indentation and text, comment and trailing blanks removed.
struct Line {
  int number = 0;
  int indent = 0;
  std::string text;
};

class Parser {
 public:
  Parser(const std::string& text, const std::string& what) : what_(what) { split(text); }

  YamlNode document() {
    YamlNode root;
    root.is_map = true;
    if (!lines_.empty()) {
      if (lines_.front().indent != 0) fail(lines_.front(), "the top-level keys must start in column 1");
      readMap(root, 0, 1);
    }
    return root;
  }

 private:
  [[noreturn]] void fail(const Line& line, const std::string& why) const { fail(line.number, why); }
  [[noreturn]] void fail(int number, const std::string& why) const {
    throw InputError(what_ + ", line " + std::to_string(number) + ": " + why);
  }

  // The text up to a comment: "#" at the start or after a blank, outside quotes.
  static std::string withoutComment(const std::string& text) {
    char quote = 0;
    for (std::size_t i = 0; i < text.size(); ++i) {
      const char c = text[i];
      if (quote != 0) {
        if (c == quote) quote = 0;
      } else if (c == '"' || c == '\'') {
        if (i == 0 || text[i - 1] == ' ' || text[i - 1] == ':') quote = c;
      } else if (c == '#' && (i == 0 || text[i - 1] == ' ' || text[i - 1] == '\t')) {
        return text.substr(0, i);
      }
    }
    return text;
  }

  static std::string trimRight(std::string s) {
    while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r')) s.pop_back();
    return s;
  }

  void split(const std::string& text) {
    bool content = false;
    int number = 0;
    std::size_t start = 0;
    while (start <= text.size()) {
      std::size_t end = text.find('\n', start);
      if (end == std::string::npos) end = text.size();
      ++number;
      const std::string raw = text.substr(start, end - start);
      start = end + 1;
      std::size_t indent = 0;
      while (indent < raw.size() && raw[indent] == ' ') ++indent;
      const std::string body = trimRight(withoutComment(raw.substr(indent)));
      if (body.empty()) continue;
      if (body[0] == '\t') fail(number, "a tab in the indentation (YAML indents with spaces)");
      if (indent == 0 && body[0] == '%') {
        if (content) fail(number, "a directive after the document started");
        continue;
      }
      if (indent == 0 && (body == "---" || body.rfind("--- ", 0) == 0)) {
        if (content) fail(number, "a second document ('---'): one map of parameters per file");
        if (body != "---") fail(number, "content after '---' on its line");
        continue;
      }
      if (indent == 0 && body == "...") break;  // end of the document
      content = true;
      lines_.push_back({number, static_cast<int>(indent), body});
    }
  }

  // Reads the keys of one map, all at indentation `indent`, from next_ on.
  void readMap(YamlNode& map, int indent, int depth) {
    if (depth > kMaxMapDepth) fail(lines_[next_], "maps nested deeper than " + std::to_string(kMaxMapDepth));
    while (next_ < lines_.size()) {
      const Line& line = lines_[next_];
      if (line.indent < indent) return;  // the map ended
      if (line.indent > indent) fail(line, "unexpected indentation");
      ++next_;
      std::string key, rest;
      splitKey(line, key, rest);
      if (map.find(key) != nullptr) fail(line, "the key '" + key + "' appears twice");
      YamlNode child;
      child.line = line.number;
      if (!rest.empty()) {
        child.scalar = scalarValue(line, rest);
      } else if (next_ < lines_.size() && lines_[next_].indent > indent) {
        child.is_map = true;
        readMap(child, lines_[next_].indent, depth + 1);
      } else {
        child.is_null = true;
      }
      map.children.emplace_back(std::move(key), std::move(child));
    }
  }

  // "key: rest" -> key (unquoted) and rest (after the colon and its blank).
  void splitKey(const Line& line, std::string& key, std::string& rest) const {
    const std::string& t = line.text;
    if (t.rfind("- ", 0) == 0 || t == "-") fail(line, "a sequence ('- '): parameters are 'key: value' maps");
    if (t[0] == '?') fail(line, "a complex key ('?')");
    std::size_t colon = std::string::npos;
    if (t[0] == '"' || t[0] == '\'') {
      const std::size_t close = t.find(t[0], 1);
      if (close == std::string::npos) fail(line, "an unterminated quoted key");
      key = t.substr(1, close - 1);
      colon = close + 1;
      if (colon >= t.size() || t[colon] != ':') fail(line, "expected ':' after the quoted key");
    } else {
      for (std::size_t i = 0; i < t.size(); ++i) {
        if (t[i] == ':' && (i + 1 == t.size() || t[i + 1] == ' ' || t[i + 1] == '\t')) {
          colon = i;
          break;
        }
      }
      if (colon == std::string::npos) fail(line, "expected 'key: value'");
      key = trimRight(t.substr(0, colon));
      if (key.empty()) fail(line, "an empty key");
      if (key.find_first_of("[]{}&*!|>") != std::string::npos) {
        fail(line, "the key '" + key + "' holds YAML syntax this reader does not take");
      }
    }
    std::size_t value = colon + 1;
    while (value < t.size() && (t[value] == ' ' || t[value] == '\t')) ++value;
    rest = t.substr(value);
  }

  std::string scalarValue(const Line& line, const std::string& rest) const {
    const char first = rest[0];
    if (first == '"' || first == '\'') {
      std::string out;
      std::size_t i = 1;
      for (; i < rest.size(); ++i) {
        const char c = rest[i];
        if (first == '\'' && c == '\'') {
          if (i + 1 < rest.size() && rest[i + 1] == '\'') {
            out += '\'';
            ++i;
            continue;
          }
          break;
        }
        if (first == '"' && c == '\\' && i + 1 < rest.size()) {
          const char e = rest[++i];
          out += e == 'n' ? '\n' : e == 't' ? '\t' : e;
          continue;
        }
        if (first == '"' && c == '"') break;
        out += c;
      }
      if (i >= rest.size()) fail(line, "an unterminated quoted value");
      if (i + 1 != rest.size()) fail(line, "text after the quoted value");
      return out;
    }
    if (first == '[' || first == '{') fail(line, "a flow collection ('" + std::string(1, first) + "'): values are numbers, booleans or words");
    if (first == '&' || first == '*') fail(line, "an anchor or alias");
    if (first == '!') fail(line, "a tag ('!')");
    if (first == '|' || first == '>') fail(line, "a block scalar ('" + std::string(1, first) + "')");
    if (first == '@' || first == '`') fail(line, "a value may not start with '" + std::string(1, first) + "'");
    if (rest.rfind("- ", 0) == 0) fail(line, "a sequence ('- ') as a value");
    return rest;
  }

  std::string what_;
  std::vector<Line> lines_;
  std::size_t next_ = 0;
};

}  // namespace

const YamlNode* YamlNode::find(const std::string& key) const {
  for (const auto& [name, node] : children) {
    if (name == key) return &node;
  }
  return nullptr;
}

std::optional<double> yamlNumber(const std::string& text, bool* out_of_range) {
  char* end = nullptr;
  errno = 0;
  const double value = std::strtod(text.c_str(), &end);
  if (out_of_range != nullptr) *out_of_range = errno == ERANGE;
  if (text.empty() || end != text.c_str() + text.size()) return std::nullopt;
  return value;
}

YamlNode parseYaml(const std::string& text, const std::string& what) {
  checkYamlText(text, what);
  return Parser(text, what).document();
}

}  // namespace oefmt
