// SPDX-License-Identifier: GPL-3.0-or-later
// Image file decoding for dataset folders and the simulator's textures: PNG (what simulators and
// recorders mostly write) through libspng, 8-bit colour PNGs through a faster decoder of the
// package's own (src/io/png_decoders.h), every other format (JPEG, TIFF, BMP, ...) through
// OpenCV's imgcodecs. Either way the result is the picture cv::imdecode(IMREAD_UNCHANGED) gives.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

namespace oefmt {

/// Largest PNG (in pixels) decodeImage accepts: 64 MP is five 4056x3040 frames; larger is a
/// corrupt or hostile header, not a camera. (Other formats have OpenCV's own limit.)
constexpr std::int64_t kMaxDecodedPixels = std::int64_t{1} << 26;

/// Decodes a PNG, JPEG, TIFF, ... file's bytes as cv::imdecode(IMREAD_UNCHANGED) would: BGR or
/// BGRA channel order, 16-bit samples kept (native-endian), a PNG's transparency (tRNS) as an
/// alpha channel except on grey images, grey + alpha as BGRA, palettes expanded, grey below 8 bits
/// scaled to 8. Throws InputError saying why when the bytes are not a readable image: no data, an
/// unknown format, a corrupt or truncated file, a PNG over kMaxDecodedPixels.
cv::Mat decodeImage(const std::uint8_t* data, std::size_t size);

/// Reads a whole file and decodes it with decodeImage. Throws InputError naming the file when it
/// is missing, unreadable, empty or not a readable image (the reason as in decodeImage).
cv::Mat readImageFile(const std::string& path);

}  // namespace oefmt
