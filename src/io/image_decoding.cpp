// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/io/image_decoding.h"

#include <libdeflate.h>

#include <algorithm>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <memory>
#include <vector>

#if defined(__SSSE3__)
#include <tmmintrin.h>
#endif

#include <opencv2/imgproc.hpp>

#include "image_codec_module.h"
#include "oefmt/error.h"

namespace oefmt {
namespace {

constexpr std::uint8_t kPngSignature[8] = {137, 80, 78, 71, 13, 10, 26, 10};
constexpr std::uint32_t kMaxChunkLength = 0x7fffffffu;  // PNG: chunk lengths are below 2^31

std::uint32_t bigEndian32(const std::uint8_t* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}

bool isPng(const std::uint8_t* data, std::size_t size) {
  return size >= 8 && std::memcmp(data, kPngSignature, 8) == 0;
}

struct PngHeader {
  std::uint32_t width = 0, height = 0;
  int bit_depth = 0, colour_type = 0, interlace = 0, compression = 0, filter = 0;
};

// The IHDR chunk right after the signature (PNG requires it first).
std::optional<PngHeader> readHeader(const std::uint8_t* data, std::size_t size) {
  if (!isPng(data, size) || size < 8 + 8 + 13 + 4) return std::nullopt;
  const std::uint8_t* chunk = data + 8;
  if (bigEndian32(chunk) != 13 || std::memcmp(chunk + 4, "IHDR", 4) != 0) return std::nullopt;
  const std::uint8_t* body = chunk + 8;
  PngHeader header;
  header.width = bigEndian32(body);
  header.height = bigEndian32(body + 4);
  header.bit_depth = body[8];
  header.colour_type = body[9];
  header.compression = body[10];
  header.filter = body[11];
  header.interlace = body[12];
  return header;
}

struct DecompressorDeleter {
  void operator()(libdeflate_decompressor* d) const { libdeflate_free_decompressor(d); }
};

libdeflate_decompressor* threadDecompressor() {
  // One per thread: a decompressor is not shareable, and making one costs an allocation.
  thread_local std::unique_ptr<libdeflate_decompressor, DecompressorDeleter> decompressor(
      libdeflate_alloc_decompressor());
  return decompressor.get();
}

// Scratch buffers reused by every decode on a thread: fresh ~1 MB allocations per frame cost
// more in page faults than the unfiltering. Buffers above kKeptScratchBytes (huge frames) are
// released after use instead of being held for the thread's lifetime.
constexpr std::size_t kKeptScratchBytes = std::size_t{16} << 20;

struct Scratch {
  std::vector<std::uint8_t> compressed, rows;
};

Scratch& threadScratch() {
  thread_local Scratch scratch;
  return scratch;
}

void releaseIfHuge(std::vector<std::uint8_t>& buffer) {
  if (buffer.capacity() > kKeptScratchBytes) std::vector<std::uint8_t>().swap(buffer);
}

// Reverses the Sub filter (each byte plus the byte kBpp to its left): a serial recurrence, one
// add per byte on its critical path. With SSSE3 (every x86-64-v2 CPU) a step takes the pixels
// of 12 or 16 bytes: their running sums within the step come from shifted adds (a prefix sum),
// then the step before's last pixel is added to all of them, so only that add and one shuffle
// per step are serial: frames whose every row is Sub-filtered (the authors' circle) decode
// several times faster.
template <int kBpp>
void unfilterSub(std::uint8_t* row, std::size_t bytes) {
  std::size_t x = 0;
#if defined(__SSSE3__)
  constexpr int kPixels = kBpp == 3 ? 4 : 16 / kBpp;  // 3 and 6 bytes: 12-byte steps
  constexpr int kStep = kPixels * kBpp;
  // The step's last pixel in every pixel slot (0x80: zero).
  alignas(16) std::uint8_t last_pixel[16];
  for (int i = 0; i < 16; ++i) {
    last_pixel[i] = static_cast<std::uint8_t>(i < kStep ? kStep - kBpp + i % kBpp : 0x80);
  }
  const __m128i spread = _mm_load_si128(reinterpret_cast<const __m128i*>(last_pixel));
  __m128i left = _mm_setzero_si128();  // left of the row: zeros
  for (; x + 16 <= bytes; x += kStep) {  // a step loads 16 bytes, stores kStep
    __m128i v = _mm_loadu_si128(reinterpret_cast<const __m128i*>(row + x));
    v = _mm_add_epi8(v, _mm_slli_si128(v, kBpp));
    if constexpr (2 * kBpp < kStep) v = _mm_add_epi8(v, _mm_slli_si128(v, 2 * kBpp));
    if constexpr (4 * kBpp < kStep) v = _mm_add_epi8(v, _mm_slli_si128(v, 4 * kBpp));
    if constexpr (8 * kBpp < kStep) v = _mm_add_epi8(v, _mm_slli_si128(v, 8 * kBpp));
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

// PNG row filters, reversed in place. `row` holds the filtered bytes of this
// row, `previous` the reconstructed previous row (zeros above the first).
template <int kBpp>
void unfilterRow(int type, std::uint8_t* row, const std::uint8_t* previous, std::size_t bytes) {
  switch (type) {
    case 0:
      return;
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
    default:
      return;  // rejected by the caller
  }
}

using UnfilterFunction = void (*)(int, std::uint8_t*, const std::uint8_t*, std::size_t);

UnfilterFunction unfilterFor(int bytes_per_pixel) {
  switch (bytes_per_pixel) {
    case 1: return &unfilterRow<1>;
    case 2: return &unfilterRow<2>;
    case 3: return &unfilterRow<3>;
    case 4: return &unfilterRow<4>;
    case 6: return &unfilterRow<6>;
    case 8: return &unfilterRow<8>;
    default: return nullptr;
  }
}

// Reconstructed 8-bit PNG rows (`stride` bytes apart) -> the cv::Mat OpenCV would give: BGR(A)
// order. OpenCV's vectorised swap: a per-pixel loop was a noticeable share of the decoding.
cv::Mat convertRows8(const std::uint8_t* first_row, std::size_t stride, int channels, int width,
                     int height) {
  const cv::Mat rows(height, width, CV_8UC(channels), const_cast<std::uint8_t*>(first_row), stride);
  cv::Mat image;
  if (channels == 1) {
    rows.copyTo(image);
  } else {
    cv::cvtColor(rows, image, channels == 3 ? cv::COLOR_RGB2BGR : cv::COLOR_RGBA2BGRA);
  }
  return image;
}

// One reconstructed 16-bit PNG row -> row y of the cv::Mat OpenCV would give: BGR(A) order,
// native-endian.
void convertRow16(const std::uint8_t* in, int channels, int width, cv::Mat& image, int y) {
  std::uint16_t* out = image.ptr<std::uint16_t>(y);
  auto sample = [in](int i) { return static_cast<std::uint16_t>((in[2 * i] << 8) | in[2 * i + 1]); };
  if (channels == 1) {
    for (int x = 0; x < width; ++x) out[x] = sample(x);
    return;
  }
  for (int x = 0; x < width; ++x) {
    const int i = x * channels;
    out[i] = sample(i + 2);
    out[i + 1] = sample(i + 1);
    out[i + 2] = sample(i);
    if (channels == 4) out[i + 3] = sample(i + 3);
  }
}

}  // namespace

std::optional<cv::Mat> decodePngFast(const std::uint8_t* data, std::size_t size) {
  const std::optional<PngHeader> header = readHeader(data, size);
  if (!header) return std::nullopt;
  int channels = 0;
  switch (header->colour_type) {
    case 0: channels = 1; break;
    case 2: channels = 3; break;
    case 6: channels = 4; break;
    default: return std::nullopt;  // palette, grey + alpha: OpenCV's conversions
  }
  if ((header->bit_depth != 8 && header->bit_depth != 16) || header->interlace != 0 ||
      header->compression != 0 || header->filter != 0 || header->width == 0 || header->height == 0 ||
      header->width > kMaxChunkLength || header->height > kMaxChunkLength ||
      static_cast<std::int64_t>(header->width) * header->height > kMaxDecodedPixels) {
    return std::nullopt;
  }
  const int width = static_cast<int>(header->width), height = static_cast<int>(header->height);
  const bool sixteen_bit = header->bit_depth == 16;
  const int bytes_per_pixel = channels * (sixteen_bit ? 2 : 1);
  const std::size_t row_bytes = static_cast<std::size_t>(width) * bytes_per_pixel;

  // Walk the chunks: CRCs checked, IDAT data gathered, anything OpenCV would treat specially
  // (transparency, an unknown critical chunk) sent back to it.
  Scratch& scratch = threadScratch();
  struct ReleaseHuge {
    Scratch& scratch;
    ~ReleaseHuge() {
      releaseIfHuge(scratch.compressed);
      releaseIfHuge(scratch.rows);
    }
  } release_huge{scratch};
  std::vector<std::uint8_t>& compressed = scratch.compressed;
  compressed.clear();
  bool ended = false;
  std::size_t offset = 8;
  while (offset + 12 <= size) {
    const std::uint32_t length = bigEndian32(data + offset);
    if (length > kMaxChunkLength || length > size - offset - 12) return std::nullopt;  // truncated
    const std::uint8_t* type = data + offset + 4;
    const std::uint8_t* body = type + 4;
    if (libdeflate_crc32(0, type, length + 4) != bigEndian32(body + length)) return std::nullopt;
    if (std::memcmp(type, "IDAT", 4) == 0) {
      compressed.insert(compressed.end(), body, body + length);
    } else if (std::memcmp(type, "IEND", 4) == 0) {
      ended = true;
      break;
    } else if (std::memcmp(type, "tRNS", 4) == 0 || std::memcmp(type, "PLTE", 4) == 0 ||
               (std::memcmp(type, "IHDR", 4) != 0 && (type[0] & 0x20) == 0)) {
      return std::nullopt;  // unknown critical chunks are upper case in their first letter
    }
    offset += 12 + static_cast<std::size_t>(length);
  }
  if (!ended || compressed.empty()) return std::nullopt;

  // Filtered rows: one filter-type byte, then the row's bytes.
  const std::size_t stride = row_bytes + 1;
  const std::size_t filtered_bytes = stride * static_cast<std::size_t>(height);
  std::vector<std::uint8_t>& rows = scratch.rows;
  if (rows.size() < filtered_bytes) rows.resize(filtered_bytes);
  std::size_t inflated = 0;
  libdeflate_decompressor* decompressor = threadDecompressor();
  if (decompressor == nullptr) return std::nullopt;  // out of memory: OpenCV may still manage
  const libdeflate_result inflate_result =
      libdeflate_zlib_decompress(decompressor, compressed.data(), compressed.size(), rows.data(),
                                 filtered_bytes, &inflated);
  if (inflate_result != LIBDEFLATE_SUCCESS || inflated != filtered_bytes) return std::nullopt;
  const UnfilterFunction unfilter = unfilterFor(bytes_per_pixel);
  if (unfilter == nullptr) return std::nullopt;
  cv::Mat image;
  if (sixteen_bit) image.create(height, width, CV_MAKETYPE(CV_16U, channels));
  const std::vector<std::uint8_t> zeros(row_bytes, 0);
  const std::uint8_t* previous = zeros.data();
  for (int y = 0; y < height; ++y) {
    std::uint8_t* row = rows.data() + static_cast<std::size_t>(y) * stride;
    if (row[0] > 4) return std::nullopt;  // not a PNG filter type
    unfilter(row[0], row + 1, previous, row_bytes);
    if (sixteen_bit) convertRow16(row + 1, channels, width, image, y);
    previous = row + 1;
  }
  if (!sixteen_bit) image = convertRows8(rows.data() + 1, stride, channels, width, height);
  return image;
}

cv::Mat decodeImage(const std::uint8_t* data, std::size_t size) {
  if (data == nullptr || size == 0) return cv::Mat();
  if (std::optional<cv::Mat> image = decodePngFast(data, size)) return std::move(*image);
  if (const std::optional<PngHeader> header = readHeader(data, size)) {
    // Both sides are below 2^32: their product fits an unsigned 64-bit integer.
    const std::uint64_t pixels = std::uint64_t{header->width} * header->height;
    if (pixels > static_cast<std::uint64_t>(kMaxDecodedPixels)) {
      throw InputError("PNG image of " + std::to_string(header->width) + "x" + std::to_string(header->height) +
                       " pixels: over the limit of " + std::to_string(kMaxDecodedPixels) + " pixels");
    }
  }
  return detail::imageCodecModule().decode(data, size);
}

cv::Mat readImageFile(const std::string& path) {
  std::ifstream file(path, std::ios::binary | std::ios::ate);
  if (!file) return cv::Mat();
  const std::streamoff length = file.tellg();
  if (length <= 0) return cv::Mat();
  // The file's bytes reuse a per-thread buffer too (see Scratch).
  thread_local std::vector<std::uint8_t> bytes;
  bytes.resize(static_cast<std::size_t>(length));
  struct ReleaseHuge {
    ~ReleaseHuge() { releaseIfHuge(bytes); }
  } release_huge;
  file.seekg(0);
  if (!file.read(reinterpret_cast<char*>(bytes.data()), length)) return cv::Mat();
  return decodeImage(bytes.data(), bytes.size());
}

}  // namespace oefmt
