// SPDX-License-Identifier: GPL-3.0-or-later
// The fast path for 8-bit RGB and RGBA PNGs (see png_decoders.h for why it exists and what it
// leaves to libspng). Whatever it is unsure of, it gives back to libspng rather than deciding.
#include "png_decoders.h"

#include <libdeflate.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <new>
#include <vector>

#if defined(__SSSE3__)
#include <tmmintrin.h>
#endif

#include <opencv2/imgproc.hpp>

#include "oefmt/io/image_decoding.h"

namespace oefmt::detail {
namespace {

constexpr std::uint8_t kPngSignature[8] = {137, 80, 78, 71, 13, 10, 26, 10};
constexpr std::uint32_t kMaxChunkLength = 0x7fffffffu;  // PNG: lengths and sizes below 2^31

std::uint32_t bigEndian32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}

bool isType(const std::uint8_t* type, const char* name) { return std::memcmp(type, name, 4) == 0; }

bool isLetter(std::uint8_t c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); }

// Critical chunks have an upper-case first letter.
bool isCritical(const std::uint8_t* type) { return (type[0] & 0x20) == 0; }

struct DecompressorDeleter {
  void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
};

libdeflate_decompressor* threadDecompressor() {
  // One per thread: a decompressor is not shareable, and making one costs an allocation.
  thread_local std::unique_ptr<libdeflate_decompressor, DecompressorDeleter> decompressor(
      libdeflate_alloc_decompressor());
  if (!decompressor) throw std::bad_alloc();
  return decompressor.get();
}

// The compressed and the inflated bytes reuse per-thread buffers: fresh megabyte allocations for
// every frame cost more in page faults than the unfiltering. Buffers grown past kKeptBytes (huge
// frames) are released after use rather than held for the thread's lifetime.
constexpr std::size_t kKeptBytes = std::size_t{16} << 20;

struct Scratch {
  std::vector<std::uint8_t> compressed, rows;
};

struct ScratchLease {
  Scratch& scratch;
  ~ScratchLease() {
    for (std::vector<std::uint8_t>* buffer : {&scratch.compressed, &scratch.rows}) {
      if (buffer->capacity() > kKeptBytes) std::vector<std::uint8_t>().swap(*buffer);
    }
  }
};

Scratch& threadScratch() {
  thread_local Scratch scratch;
  return scratch;
}

// Reverses the Sub filter (each byte plus the byte kBpp to its left): a serial recurrence, one
// add per byte on its critical path. With SSSE3 a step takes the pixels of 12 or 16 bytes: their
// running sums within the step come from shifted adds (a prefix sum), then the previous step's
// last pixel is added to all of them, so only that add and one shuffle per step are serial.
// Writers that Sub-filter every row (common for photographs and renders) decode several times
// faster for it.
template <int kBpp>
void unfilterSub(std::uint8_t* row, std::size_t bytes) {
  std::size_t x = 0;
#if defined(__SSSE3__)
  constexpr int kPixels = kBpp == 3 ? 4 : 16 / kBpp;  // 3 bytes per pixel: 12-byte steps
  constexpr int kStep = kPixels * kBpp;
  // The step's last pixel in every pixel slot (0x80: zero).
  alignas(16) std::uint8_t last_pixel[16];
  for (int i = 0; i < 16; ++i) {
    last_pixel[i] = static_cast<std::uint8_t>(i < kStep ? kStep - kBpp + i % kBpp : 0x80);
  }
  const __m128i spread = _mm_load_si128(reinterpret_cast<const __m128i*>(last_pixel));
  __m128i left = _mm_setzero_si128();  // left of the row: zeros
  for (; x + 16 <= bytes; x += kStep) {  // a step loads 16 bytes and stores kStep
    __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x));
    v = _mm_add_epi8(v, _mm_slli_si128(v, kBpp));
    if constexpr (2 * kBpp < kStep) v = _mm_add_epi8(v, _mm_slli_si128(v, 2 * kBpp));
    if constexpr (4 * kBpp < kStep) v = _mm_add_epi8(v, _mm_slli_si128(v, 4 * kBpp));
    v = _mm_add_epi8(v, left);
    if constexpr (kStep == 16) {
      _mm_storeu_si128(reinterpret_cast<__m128i*>(row + x), v);
    } else {
      _mm_storel_epi64(reinterpret_cast<__m128i*>(row + x), v);
      const std::uint32_t high = static_cast<std::uint32_t>(_mm_cvtsi128_si32(_mm_srli_si128(v, 8)));
      std::memcpy(row + x + 8, &high, 4);
    }
    left = _mm_shuffle_epi8(v, spread);
  }
#endif
  for (x = std::max<std::size_t>(x, kBpp); x < bytes; ++x) {
    row[x] = static_cast<std::uint8_t>(row[x] + row[x - kBpp]);
  }
}

// Reverses one row's filter in place: `row` holds its filtered bytes, `previous` the
// reconstructed row above (zeros above the first).
template <int kBpp>
void unfilterRow(int type, std::uint8_t* row, const std::uint8_t* previous, std::size_t bytes) {
  switch (type) {
    case 1:  // Sub
      unfilterSub<kBpp>(row, bytes);
      return;
    case 2:  // Up
      for (std::size_t x = 0; x < bytes; ++x) row[x] = static_cast<std::uint8_t>(row[x] + previous[x]);
      return;
    case 3:  // Average
      for (std::size_t x = 0; x < kBpp && x < bytes; ++x) {
        row[x] = static_cast<std::uint8_t>(row[x] + (previous[x] >> 1));
      }
      for (std::size_t x = kBpp; x < bytes; ++x) {
        row[x] = static_cast<std::uint8_t>(row[x] + ((row[x - kBpp] + previous[x]) >> 1));
      }
      return;
    case 4:  // Paeth
      for (std::size_t x = 0; x < kBpp && x < bytes; ++x) row[x] = static_cast<std::uint8_t>(row[x] + previous[x]);
      for (std::size_t x = kBpp; x < bytes; ++x) {
        const int a = row[x - kBpp], b = previous[x], c = previous[x - kBpp];
        const int pa = std::abs(b - c), pb = std::abs(a - c), pc = std::abs(a + b - 2 * c);
        const int predictor = (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
        row[x] = static_cast<std::uint8_t>(row[x] + predictor);
      }
      return;
    default:  // None
      return;
  }
}

struct Header {
  int width = 0, height = 0, channels = 0;
};

// The IHDR chunk, which PNG puts first: a kind this path takes, or nothing.
std::optional<Header> readHeader(const std::uint8_t* data, std::size_t size) {
  if (size < 8 + 12 + 13 || std::memcmp(data, kPngSignature, 8) != 0) return std::nullopt;
  const std::uint8_t* chunk = data + 8;
  if (bigEndian32(chunk) != 13 || !isType(chunk + 4, "IHDR")) return std::nullopt;
  const std::uint8_t* body = chunk + 8;
  const std::uint32_t width = bigEndian32(body), height = bigEndian32(body + 4);
  const int bit_depth = body[8], colour_type = body[9], compression = body[10], filter = body[11],
            interlace = body[12];
  if (bit_depth != 8 || (colour_type != 2 && colour_type != 6) || compression != 0 || filter != 0 ||
      interlace != 0 || width == 0 || height == 0 || width > kMaxChunkLength || height > kMaxChunkLength ||
      std::int64_t{width} * height > kMaxDecodedPixels) {
    return std::nullopt;
  }
  return Header{static_cast<int>(width), static_cast<int>(height), colour_type == 2 ? 3 : 4};
}

// Walks the chunks after IHDR, checking every CRC, and gathers the image data. Nothing when the
// file is not plainly one picture: a second IHDR, a palette or transparency, an unknown critical
// chunk, image data split by other chunks, a malformed chunk name, no IEND.
bool gatherImageData(const std::uint8_t* data, std::size_t size, std::vector<std::uint8_t>& compressed) {
  compressed.clear();
  bool data_seen = false, data_ended = false;
  for (std::size_t offset = 8; offset + 12 <= size;) {
    const std::uint32_t length = bigEndian32(data + offset);
    if (length > kMaxChunkLength || length > size - offset - 12) return false;
    const std::uint8_t* type = data + offset + 4;
    const std::uint8_t* body = type + 4;
    if (!std::all_of(type, type + 4, isLetter)) return false;
    if (libdeflate_crc32(0, type, length + std::size_t{4}) != bigEndian32(body + length)) return false;
    const bool image_data = isType(type, "IDAT");
    if (image_data) {
      if (data_ended) return false;
      data_seen = true;
      compressed.insert(compressed.end(), body, body + length);
    } else {
      data_ended = data_seen;
      if (isType(type, "IEND")) return length == 0 && data_seen;
      if (offset != 8 && (isCritical(type) || isType(type, "tRNS"))) return false;
    }
    offset += 12 + std::size_t{length};
  }
  return false;  // cut short before IEND
}

}  // namespace

std::optional<cv::Mat> decodeColourPngFast(const std::uint8_t* data, std::size_t size) {
  if (data == nullptr) return std::nullopt;
  const std::optional<Header> header = readHeader(data, size);
  if (!header) return std::nullopt;
  Scratch& scratch = threadScratch();
  const ScratchLease lease{scratch};
  if (!gatherImageData(data, size, scratch.compressed)) return std::nullopt;

  // Filtered rows: a filter-type byte, then the row's samples. The zlib stream must fill them
  // exactly and end where the image data ends (its Adler-32 checked by libdeflate).
  const int channels = header->channels;
  const std::size_t row_bytes = static_cast<std::size_t>(header->width) * channels;
  const std::size_t stride = row_bytes + 1;
  const std::size_t filtered_bytes = stride * static_cast<std::size_t>(header->height);
  std::vector<std::uint8_t>& rows = scratch.rows;
  if (rows.size() < filtered_bytes) rows.resize(filtered_bytes);
  std::size_t consumed = 0, inflated = 0;
  const libdeflate_result result =
      libdeflate_zlib_decompress_ex(threadDecompressor(), scratch.compressed.data(), scratch.compressed.size(),
                                    rows.data(), filtered_bytes, &consumed, &inflated);
  if (result != LIBDEFLATE_SUCCESS || consumed != scratch.compressed.size() || inflated != filtered_bytes) {
    return std::nullopt;
  }

  // Unfiltered a block of rows at a time, then swapped to OpenCV's BGR(A) order by its vectorised
  // conversion while the block is still in cache.
  constexpr int kBlockRows = 16;
  const auto unfilter = channels == 3 ? &unfilterRow<3> : &unfilterRow<4>;
  const int swap_code = channels == 3 ? cv::COLOR_RGB2BGR : cv::COLOR_RGBA2BGRA;
  cv::Mat image(header->height, header->width, CV_8UC(channels));
  const std::vector<std::uint8_t> zeros(row_bytes, 0);
  const std::uint8_t* previous = zeros.data();
  for (int first = 0; first < header->height; first += kBlockRows) {
    const int last = std::min(first + kBlockRows, header->height);
    for (int y = first; y < last; ++y) {
      std::uint8_t* row = rows.data() + static_cast<std::size_t>(y) * stride;
      if (row[0] > 4) return std::nullopt;  // not a PNG filter type
      unfilter(row[0], row + 1, previous, row_bytes);
      previous = row + 1;
    }
    const cv::Mat block(last - first, header->width, CV_8UC(channels),
                        rows.data() + static_cast<std::size_t>(first) * stride + 1, stride);
    cv::cvtColor(block, image.rowRange(first, last), swap_code);
  }
  return image;
}

}  // namespace oefmt::detail
