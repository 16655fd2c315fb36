// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/io/fft_wisdom.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>

#include "oefmt/registration/fft.h"

namespace oefmt {

std::string defaultFftWisdomPath() {
  if (const char* explicit_path = std::getenv("OEFMT_FFTW_WISDOM")) {
    const std::string path(explicit_path);
    return path == "none" ? std::string() : path;
  }
  std::filesystem::path cache;
  if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg != nullptr && xdg[0] == '/') {
    cache = xdg;
  } else if (const char* home = std::getenv("HOME"); home != nullptr && home[0] == '/') {
    cache = std::filesystem::path(home) / ".cache";
  } else {
    return std::string();
  }
  char host[256] = {};
  if (::gethostname(host, sizeof(host) - 1) != 0 || host[0] == '\0') std::snprintf(host, sizeof(host), "unknown");
  return (cache / "oefmt" / (std::string("fftwf-wisdom-") + host)).string();
}

void useDefaultFftWisdom() { setFftWisdomFile(defaultFftWisdomPath()); }

}  // namespace oefmt
