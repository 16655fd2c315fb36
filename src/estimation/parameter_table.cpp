// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/estimation/parameter_table.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "oefmt/error.h"

namespace oefmt {
namespace {

// The shortest text that reads back as the same double, without an exponent from 1e-4 to
// 1e15 (1000, not 1e+03), elsewhere an exponent without leading zeros (1e-6).
std::string shortestText(double v) {
  if (!std::isfinite(v)) return std::isnan(v) ? "nan" : v > 0.0 ? "inf" : "-inf";
  char buffer[64];
  int precision = 1;
  for (; precision < 17; ++precision) {
    std::snprintf(buffer, sizeof(buffer), "%.*g", precision, v);
    if (std::strtod(buffer, nullptr) == v) break;
  }
  const int exponent = v == 0.0 ? 0 : static_cast<int>(std::floor(std::log10(std::fabs(v))));
  if (exponent >= precision && exponent < 15) precision = exponent + 1;
  std::snprintf(buffer, sizeof(buffer), "%.*g", precision, v);
  std::string s = buffer;
  const auto e = s.find('e');
  if (e == std::string::npos) return s;
  std::string digits = s.substr(e + 2);
  digits.erase(0, std::min(digits.find_first_not_of('0'), digits.size() - 1));
  return s.substr(0, e + 2) + digits;  // the sign kept: YAML 1.1 wants it (1.0e+20)
}

// A number as a configuration file writes it: with a dot, which YAML 1.1 readers such as
// rosparam's need to take 1.0e-6 for a number (1e-6 is a string to them).
std::string formatNumber(double v) {
  std::string s = shortestText(v);
  if (s.find_first_of(".ein") == std::string::npos) return s + ".0";
  const auto e = s.find('e');
  if (e != std::string::npos && s.find('.') == std::string::npos) s.insert(e, ".0");
  return s;
}

// "must be in [1, 10], got 0", "must be >= 0, got -1".
std::string outside(const ParameterRange& range, const std::string& got) {
  const std::string text = range.text();
  const bool interval = !text.empty() && (text[0] == '[' || text[0] == '(');
  return std::string("must be ") + (interval ? "in " : "") + text + ", got " + got;
}

const char* kindOf(ParameterType type) {
  switch (type) {
    case ParameterType::kNumber: return "a number";
    case ParameterType::kInteger: return "an integer";
    case ParameterType::kBoolean: return "true or false";
    case ParameterType::kWord: return "a word";
    case ParameterType::kText: return "text";
  }
  return "a value";
}

}  // namespace

bool ParameterRange::contains(double value) const {
  if (!std::isfinite(value)) return false;
  if (min_open ? !(value > min) : !(value >= min)) return false;
  if (max_open ? !(value < max) : !(value <= max)) return false;
  return !even || std::fmod(value, 2.0) == 0.0;
}

std::string ParameterRange::text() const {
  const bool has_min = std::isfinite(min), has_max = std::isfinite(max);
  std::string bounds;
  if (has_min && has_max) {
    bounds = std::string(min_open ? "(" : "[") + shortestText(min) + ", " + shortestText(max) +
             (max_open ? ")" : "]");
  } else if (has_min) {
    bounds = std::string(min_open ? "> " : ">= ") + shortestText(min);
  } else if (has_max) {
    bounds = std::string(max_open ? "< " : "<= ") + shortestText(max);
  }
  if (!even) return bounds;
  return bounds.empty() ? "even" : "even, " + bounds;
}

ParameterRange closedRange(double min, double max) {
  ParameterRange r;
  r.min = min;
  r.max = max;
  return r;
}

ParameterRange atLeast(double min) {
  ParameterRange r;
  r.min = min;
  return r;
}

ParameterRange above(double min) {
  ParameterRange r = atLeast(min);
  r.min_open = true;
  return r;
}

std::string Parameter::section() const {
  const auto dot = key.find('.');
  return dot == std::string::npos ? std::string() : key.substr(0, dot);
}

std::string Parameter::name() const {
  const auto dot = key.find('.');
  return dot == std::string::npos ? key : key.substr(dot + 1);
}

std::string Parameter::valueText() const {
  switch (type) {
    case ParameterType::kNumber: return formatNumber(*number);
    case ParameterType::kInteger: return std::to_string(*integer);
    case ParameterType::kBoolean: return *boolean ? "true" : "false";
    case ParameterType::kWord: return get_word();
    case ParameterType::kText: return *text;
  }
  return "";
}

std::string Parameter::rule() const {
  std::string out;
  if (type == ParameterType::kNumber || type == ParameterType::kInteger) out = range.text();
  if (type == ParameterType::kWord) out = wordList(words);
  if (!extra_rule.empty()) out += (out.empty() ? "" : ", ") + extra_rule;
  return out;
}

std::string Parameter::problem() const {
  switch (type) {
    case ParameterType::kNumber:
      if (range.contains(*number)) return "";
      return outside(range, shortestText(*number));
    case ParameterType::kInteger:
      if (range.contains(*integer)) return "";
      return outside(range, std::to_string(*integer));
    case ParameterType::kWord: {
      const std::string word = get_word();
      if (std::find(words.begin(), words.end(), word) != words.end()) return "";
      return "must be " + wordList(words);
    }
    case ParameterType::kBoolean:
    case ParameterType::kText: return "";
  }
  return "";
}

void Parameter::setNumber(double value) const {
  if (type == ParameterType::kNumber) {
    if (!std::isfinite(value)) throwInvalidParameter(key, "expected a finite number");
    if (!range.contains(value)) throwInvalidParameter(key, outside(range, shortestText(value)));
    *number = value;
    return;
  }
  if (type != ParameterType::kInteger) throwInvalidParameter(key, std::string("expected ") + kindOf(type));
  // Beyond 1e9 no integer parameter means anything, and int must hold it.
  if (!(std::fabs(value) < 1e9) || value != std::floor(value)) {
    throwInvalidParameter(key, "expected an integer, got " + shortestText(value));
  }
  if (!range.contains(value)) throwInvalidParameter(key, outside(range, shortestText(value)));
  *integer = static_cast<int>(value);
}

void Parameter::setBoolean(bool value) const {
  if (type != ParameterType::kBoolean) throwInvalidParameter(key, std::string("expected ") + kindOf(type));
  *boolean = value;
}

void Parameter::setWord(const std::string& value) const {
  if (type == ParameterType::kText) {
    *text = value;
    return;
  }
  if (type != ParameterType::kWord) throwInvalidParameter(key, std::string("expected ") + kindOf(type));
  if (std::find(words.begin(), words.end(), value) == words.end()) {
    throwInvalidParameter(key, "expected " + wordList(words) + ", got '" + value + "'");
  }
  set_word(value);
}

Parameter numberParameter(const std::string& key, double& field, const std::string& unit,
                          ParameterRange range, const std::string& meaning) {
  Parameter p;
  p.key = key;
  p.type = ParameterType::kNumber;
  p.unit = unit;
  p.range = range;
  p.meaning = meaning;
  p.number = &field;
  return p;
}

Parameter integerParameter(const std::string& key, int& field, const std::string& unit,
                           ParameterRange range, const std::string& meaning) {
  Parameter p;
  p.key = key;
  p.type = ParameterType::kInteger;
  p.unit = unit;
  p.range = range;
  p.meaning = meaning;
  p.integer = &field;
  return p;
}

Parameter booleanParameter(const std::string& key, bool& field, const std::string& meaning) {
  Parameter p;
  p.key = key;
  p.type = ParameterType::kBoolean;
  p.meaning = meaning;
  p.boolean = &field;
  return p;
}

Parameter textParameter(const std::string& key, std::string& field, const std::string& meaning) {
  Parameter p;
  p.key = key;
  p.type = ParameterType::kText;
  p.meaning = meaning;
  p.text = &field;
  return p;
}

const Parameter* findParameter(const ParameterTable& table, const std::string& key) {
  for (const Parameter& p : table) {
    if (p.key == key) return &p;
  }
  return nullptr;
}

bool isParameterSection(const ParameterTable& table, const std::string& section) {
  if (section.empty()) return false;
  return std::any_of(table.begin(), table.end(), [&](const Parameter& p) { return p.section() == section; });
}

void checkParameters(const ParameterTable& table, const std::string& prefix) {
  for (const Parameter& p : table) {
    if (p.key.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string problem = p.problem();
    if (!problem.empty()) throwInvalidParameter(p.key, problem);
  }
}

}  // namespace oefmt
