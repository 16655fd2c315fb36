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

}  // namespace oefmt
