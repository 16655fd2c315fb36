// SPDX-License-Identifier: GPL-3.0-or-later
// Image file decoding for datasets and compressed image messages. PNG is what simulators and
// bag recorders write, and OpenCV's libpng + zlib path takes longer on a frame than the
// registration: common PNGs get a fast path (libdeflate inflate, tight unfilter loops),
// everything else goes to cv::imdecode. OpenCV's imgcodecs is not linked: it is loaded on first
// use (liboefmt_image_codecs.so, beside liboefmt_io.so), as linking it costs every process
// start-up time and memory for libraries the PNG path never needs (doc/performance.md).
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

namespace oefmt {

/// Largest image (in pixels) any decoder here accepts: 64 MP is five 4056x3040 frames; larger
/// is a corrupt or hostile header, not a camera.
constexpr std::int64_t kMaxDecodedPixels = std::int64_t{1} << 26;

/// The fast path alone: non-interlaced 8/16-bit grey, RGB and RGBA PNGs without a tRNS chunk,
/// decoded exactly as cv::imdecode(IMREAD_UNCHANGED) would (BGR/BGRA order, native-endian 16
/// bit). Returns nullopt for anything else: other PNG features, other formats, damaged data
/// (bad CRC, bad zlib stream, truncation) or an image over kMaxDecodedPixels.
std::optional<cv::Mat> decodePngFast(const std::uint8_t* data, std::size_t size);

/// Decodes PNG, JPEG, TIFF, ... as cv::imdecode(IMREAD_UNCHANGED), PNGs through decodePngFast.
/// Returns an empty Mat when the data is not a readable image; throws InputError for an image
/// header over kMaxDecodedPixels (the message gives its size), std::runtime_error when an image
/// needs imgcodecs and its plugin cannot be loaded.
cv::Mat decodeImage(const std::uint8_t* data, std::size_t size);

/// Reads a whole file and decodes it with decodeImage. Empty Mat when the file cannot be read
/// or decoded; InputError as in decodeImage.
cv::Mat readImageFile(const std::string& path);

}  // namespace oefmt
