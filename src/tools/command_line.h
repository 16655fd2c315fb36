// SPDX-License-Identifier: GPL-3.0-or-later
// Command-line reading shared by the tools: options, their values and checked numbers. A missing
// or malformed value is an oefmt::InputError naming the option; the tools exit 2 on it.
#pragma once

#include <cmath>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "oefmt/error.h"

namespace oefmt {
namespace tools {

/// `text` as a finite number, or an InputError naming `option`.
inline double toNumber(const std::string& option, const std::string& text) {
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (end == text.c_str() || *end != '\0' || !std::isfinite(v)) {
    throw InputError("option " + option + " needs a number, got '" + text + "'");
  }
  return v;
}

/// "a,b,c" as finite numbers, or an InputError naming `option`.
inline std::vector<double> numberList(const std::string& option, const std::string& text) {
  std::vector<double> values;
  std::stringstream stream(text);
  std::string item;
  while (std::getline(stream, item, ',')) {
    try {
      values.push_back(toNumber(option, item));
    } catch (const InputError&) {  // name the whole list, not the item
      throw InputError("option " + option + " needs numbers separated by commas, got '" + text + "'");
    }
  }
  return values;
}

/// argv read one item at a time.
class Arguments {
 public:
  Arguments(int argc, char** argv) : args_(argv + 1, argv + argc) {}
  bool done() const { return index_ >= args_.size(); }
  std::string take() { return args_[index_++]; }
  /// The value after `option`.
  std::string value(const std::string& option) {
    if (done()) throw InputError("option " + option + " needs a value");
    return take();
  }
  double number(const std::string& option) { return toNumber(option, value(option)); }
  int integer(const std::string& option) {
    const double v = number(option);
    if (v != std::floor(v) || std::fabs(v) > 1e9) throw InputError("option " + option + " needs an integer");
    return static_cast<int>(v);
  }

 private:
  std::vector<std::string> args_;
  std::size_t index_ = 0;
};

}  // namespace tools
}  // namespace oefmt
