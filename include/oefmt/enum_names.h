// SPDX-License-Identifier: GPL-3.0-or-later
// One table of names per enum: printing a value (toString) and reading a word (parseEnum) both
// read it, so a new value is named once and every error message lists the words accepted.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "oefmt/error.h"

namespace oefmt {

template <typename T>
struct EnumName {
  T value;
  const char* name;
};

/// The name of `value` in `names` ("unknown" for a value the table lacks).
template <typename T, std::size_t N>
constexpr const char* enumName(const EnumName<T> (&names)[N], T value) {
  for (const EnumName<T>& entry : names) {
    if (entry.value == value) return entry.name;
  }
  return "unknown";
}

/// The value named `text` exactly (case matters), or nullopt.
template <typename T, std::size_t N>
std::optional<T> findEnum(const EnumName<T> (&names)[N], const std::string& text) {
  for (const EnumName<T>& entry : names) {
    if (text == entry.name) return entry.value;
  }
  return std::nullopt;
}

/// The names in table order.
template <typename T, std::size_t N>
std::vector<std::string> enumNames(const EnumName<T> (&names)[N]) {
  std::vector<std::string> out;
  for (const EnumName<T>& entry : names) out.emplace_back(entry.name);
  return out;
}

/// "a, b or c".
inline std::string wordList(const std::vector<std::string>& words) {
  std::string out;
  for (std::size_t i = 0; i < words.size(); ++i) {
    if (i > 0) out += i + 1 == words.size() ? " or " : ", ";
    out += words[i];
  }
  return out;
}

/// The value named `text`; otherwise an InputError "unknown <what> 'text': expected a, b or c".
template <typename T, std::size_t N>
T parseEnum(const EnumName<T> (&names)[N], const std::string& text, const std::string& what) {
  if (const std::optional<T> value = findEnum(names, text)) return *value;
  throw InputError("unknown " + what + " '" + text + "': expected " + wordList(enumNames(names)));
}

}  // namespace oefmt
