// SPDX-License-Identifier: GPL-3.0-or-later
#include "image_codec_module.h"

#include <dlfcn.h>

#include <filesystem>
#include <stdexcept>

namespace oefmt {
namespace detail {
namespace {

struct Loaded {
  const ImageCodecModule* module = nullptr;
  std::string error;  // why not, when module is null
};

// The directory of the file this code was loaded from: liboefmt_io.so, or the executable a
// static core is linked into. The plugin is built and installed beside it.
std::string ownDirectory() {
  Dl_info info{};
  if (::dladdr(reinterpret_cast<const void*>(&imageCodecModule), &info) == 0 ||
      info.dli_fname == nullptr) {
    return std::string();
  }
  return std::filesystem::path(info.dli_fname).parent_path().string();
}

Loaded load() {
  Loaded loaded;
  std::vector<std::string> candidates;
  const std::string directory = ownDirectory();
  if (!directory.empty()) {
    candidates.push_back((std::filesystem::path(directory) / kImageCodecModuleFile).string());
  }
  candidates.emplace_back(kImageCodecModuleFile);  // LD_LIBRARY_PATH, the loader's cache
  for (const std::string& candidate : candidates) {
    void* handle = ::dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
      const char* reason = ::dlerror();
      loaded.error += "\n  " + (reason ? std::string(reason) : candidate + ": not loadable");
      continue;
    }
    using Entry = const ImageCodecModule* (*)();
    const auto entry = reinterpret_cast<Entry>(::dlsym(handle, kImageCodecModuleSymbol));
    const ImageCodecModule* module = entry ? entry() : nullptr;
    if (module == nullptr || module->version != kImageCodecModuleVersion) {
      loaded.error += "\n  " + candidate + ": not this version's plugin (rebuild oefmt)";
      ::dlclose(handle);
      continue;
    }
    loaded.module = module;  // kept loaded for the rest of the process
    return loaded;
  }
  loaded.error = std::string("cannot load the image codec plugin ") + kImageCodecModuleFile +
                 " (OpenCV imgcodecs, needed for this image; it is built and installed with oefmt):" +
                 loaded.error;
  return loaded;
}

}  // namespace

const ImageCodecModule& imageCodecModule() {
  static const Loaded loaded = load();  // thread-safe, once per process
  if (loaded.module == nullptr) throw std::runtime_error(loaded.error);
  return *loaded.module;
}

}  // namespace detail
}  // namespace oefmt
