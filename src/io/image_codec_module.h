// SPDX-License-Identifier: GPL-3.0-or-later
// Private to src/io and src/codecs: OpenCV's imgcodecs, loaded on first use. Linking it costs
// every process start-up time and memory (it pulls in GDAL, HDF5, Poppler, ... about 150
// libraries) although the common PNGs never need it (decodePngFast). So the core reaches it
// through liboefmt_image_codecs.so (src/codecs), a plugin it dlopen()s the first time an image
// needs it (another format, an unusual PNG, an encoding).
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace oefmt {
namespace detail {

/// Bumped whenever ImageCodecModule changes: a stale plugin is refused, not called.
constexpr int kImageCodecModuleVersion = 1;

/// What the plugin exports (built by the same compiler from the same tree as the core).
struct ImageCodecModule {
  int version;
  /// cv::imdecode(IMREAD_UNCHANGED); an empty Mat when unreadable (OpenCV exceptions included).
  cv::Mat (*decode)(const std::uint8_t* data, std::size_t size);
  /// cv::imencode as `extension` ("png", "jpg", ...): true, or false with `error` set.
  bool (*encode)(const std::string& extension, const cv::Mat& image,
                 std::vector<std::uint8_t>& bytes, std::string& error);
};

/// The plugin's file name, and the symbol that returns its table.
constexpr const char* kImageCodecModuleFile = "liboefmt_image_codecs.so";
constexpr const char* kImageCodecModuleSymbol = "oefmt_image_codec_module";

/// The loaded plugin (loaded once per process, never unloaded). Looked for next to the core
/// library (or the executable the core is linked into), then on the loader's search path.
/// Throws std::runtime_error naming the files tried and the loader's reason when it cannot be
/// loaded.
const ImageCodecModule& imageCodecModule();

}  // namespace detail
}  // namespace oefmt
