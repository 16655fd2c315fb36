// SPDX-License-Identifier: GPL-3.0-or-later
#pragma once

#include <stdexcept>
#include <string>

namespace oefmt {

/// Thrown at the API edge of the core when an input cannot be used at all (empty image, unknown
/// pixel type, mismatched sizes, bad configuration). The message says what was wrong and why.
class InputError : public std::invalid_argument {
 public:
  explicit InputError(const std::string& what) : std::invalid_argument(what) {}
};

/// The validate() functions' check: an InputError with `message` unless `ok`.
inline void requireInput(bool ok, const std::string& message) {
  if (!ok) throw InputError(message);
}

/// A configuration value refused: the InputError "invalid parameter 'KEY': WHY".
[[noreturn]] inline void throwInvalidParameter(const std::string& key, const std::string& why) {
  throw InputError("invalid parameter '" + key + "': " + why);
}

/// A configuration value's check: throwInvalidParameter(field, rule) unless `ok`.
inline void requireParameter(bool ok, const std::string& field, const std::string& rule) {
  if (!ok) throwInvalidParameter(field, rule);
}

}  // namespace oefmt
