// SPDX-License-Identifier: GPL-3.0-or-later
// The two PNG decoders behind decodeImage (oefmt/io/image_decoding.h).
//
// libspng reads every PNG kind and is the reference. For 8-bit RGB and RGBA files, the kind
// colour cameras and simulators write, a fast path of our own comes first: libdeflate's inflater
// (about twice zlib's speed, which is most of libspng's time) and SSSE3 row unfiltering, into
// buffers reused from frame to frame. It makes whole oefmt_offline runs over colour folders
// markedly faster (doc/performance.md, Image decoding), which is the only reason it exists. It
// takes only files it can read without doubt and gives back nothing for anything else (another
// kind, transparency, interlacing, a bad checksum, an unexpected chunk, a damaged stream), which
// libspng then decodes or refuses with its reason.
#pragma once

#include <cstddef>
#include <cstdint>
#include <optional>

#include <opencv2/core.hpp>

namespace oefmt::detail {

/// Any PNG, as decodeImage documents; throws InputError saying why when it cannot.
cv::Mat decodePngLibspng(const std::uint8_t* data, std::size_t size);

/// A non-interlaced 8-bit RGB or RGBA PNG without transparency chunk, checksums and structure
/// intact: the same picture as decodePngLibspng. Nothing for every other file. Never throws
/// InputError (std::bad_alloc when memory runs out).
std::optional<cv::Mat> decodeColourPngFast(const std::uint8_t* data, std::size_t size);

}  // namespace oefmt::detail
