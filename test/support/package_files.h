// SPDX-License-Identifier: GPL-3.0-or-later
// Files of the package's own tree the tests compare against (generated docs and defaults), and
// whole files read as text.
#pragma once

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace oefmt {
namespace test {

/// The package root, from this header's path (test/support/package_files.h).
inline std::filesystem::path packageRoot() {
  return std::filesystem::path(__FILE__).parent_path().parent_path().parent_path();
}

/// The whole file as bytes; empty when it cannot be read.
inline std::string readFile(const std::filesystem::path& path) {
  std::ifstream file(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(file)), std::istreambuf_iterator<char>());
}

}  // namespace test
}  // namespace oefmt
