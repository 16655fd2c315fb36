// SPDX-License-Identifier: GPL-3.0-or-later
// Every PNG kind through libspng: the reference decoder (see png_decoders.h).
#include "png_decoders.h"

#include <spng.h>

#include <algorithm>
#include <memory>
#include <new>
#include <string>

#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"
#include "oefmt/io/image_decoding.h"

namespace oefmt::detail {
namespace {

// Ancillary chunks (text, ICC profiles, ...) are never used here: a file may not make libspng
// hold more than this of them, inflated (its default is unlimited).
constexpr std::size_t kMaxAncillaryBytes = std::size_t{1} << 24;

struct ContextDeleter {
  void operator()(spng_ctx* context) const { spng_ctx_free(context); }
};
using Context = std::unique_ptr<spng_ctx, ContextDeleter>;

void check(int code, const char* what) {
  if (code != SPNG_OK) {
    if (code == SPNG_EMEM) throw std::bad_alloc();
    throw InputError(std::string("corrupt or unsupported PNG (") + what + ": " + spng_strerror(code) + ")");
  }
}

// How libspng is asked for a PNG's samples so that they give cv::imdecode(IMREAD_UNCHANGED)'s
// picture once red and blue are swapped: OpenCV keeps the bit depth, ignores a grey image's
// tRNS, turns any other tRNS into an alpha channel (for a palette: when it lists at least one
// entry), and copies grey + alpha into BGRA.
struct Layout {
  int format = 0;  // spng_format
  int flags = 0;   // spng_decode_flags
  int type = 0;    // the cv::Mat type
};

Layout layoutFor(const spng_ihdr& header, bool transparency) {
  const bool sixteen = header.bit_depth == 16;
  const int depth = sixteen ? CV_16U : CV_8U;
  // SPNG_FMT_PNG: the file's own samples (host-endian), no conversion.
  switch (header.color_type) {
    case SPNG_COLOR_TYPE_GRAYSCALE:  // G8 scales 1, 2 and 4-bit grey to 8 bits, as OpenCV does
      return {sixteen ? SPNG_FMT_PNG : SPNG_FMT_G8, 0, CV_MAKETYPE(depth, 1)};
    case SPNG_COLOR_TYPE_TRUECOLOR:
    case SPNG_COLOR_TYPE_INDEXED:  // palettes are 8 bits or fewer
      if (transparency) return {sixteen ? SPNG_FMT_RGBA16 : SPNG_FMT_RGBA8, SPNG_DECODE_TRNS, CV_MAKETYPE(depth, 4)};
      return {sixteen ? SPNG_FMT_PNG : SPNG_FMT_RGB8, 0, CV_MAKETYPE(depth, 3)};
    default:  // grey + alpha, RGBA
      return {sixteen ? SPNG_FMT_RGBA16 : SPNG_FMT_RGBA8, 0, CV_MAKETYPE(depth, 4)};
  }
}

}  // namespace

cv::Mat decodePngLibspng(const std::uint8_t* data, std::size_t size) {
  const Context context(spng_ctx_new(0));
  if (!context) throw std::bad_alloc();
  spng_ctx* png = context.get();
  check(spng_set_chunk_limits(png, kMaxAncillaryBytes, kMaxAncillaryBytes), "chunk limits");
  check(spng_set_png_buffer(png, data, size), "buffer");
  spng_ihdr header{};
  check(spng_get_ihdr(png, &header), "header");
  // Both sides are below 2^31 (libspng checks): their product fits a 64-bit integer.
  if (std::int64_t{header.width} * header.height > kMaxDecodedPixels) {
    throw InputError("PNG image of " + std::to_string(header.width) + "x" + std::to_string(header.height) +
                     " pixels: over the limit of " + std::to_string(kMaxDecodedPixels) + " pixels");
  }
  spng_trns trns{};
  const int trns_found = spng_get_trns(png, &trns);
  if (trns_found != SPNG_ECHUNKAVAIL) check(trns_found, "transparency");
  const bool transparency = trns_found == SPNG_OK && header.color_type != SPNG_COLOR_TYPE_GRAYSCALE &&
                            (header.color_type != SPNG_COLOR_TYPE_INDEXED || trns.n_type3_entries > 0);
  const Layout layout = layoutFor(header, transparency);

  cv::Mat image(static_cast<int>(header.height), static_cast<int>(header.width), layout.type);
  const std::size_t row_bytes = image.cols * image.elemSize();
  std::size_t bytes = 0;
  check(spng_decoded_image_size(png, layout.format, &bytes), "image size");
  if (bytes != row_bytes * image.rows) {
    throw InputError("unsupported PNG (bit depth " + std::to_string(header.bit_depth) + ", colour type " +
                     std::to_string(header.color_type) + ")");
  }
  check(spng_decode_image(png, nullptr, 0, layout.format, layout.flags | SPNG_DECODE_PROGRESSIVE), "image data");
  // Row by row. Colour rows go through a block of kBlockRows rows that stays in cache, from which
  // OpenCV's vectorised swap writes them in BGR(A) order: a whole decoded RGB image swapped
  // afterwards is one more pass over memory. Grey rows, and the rows of an interlaced image
  // (which every pass revisits), are decoded in place.
  constexpr int kBlockRows = 16;
  const bool swap = image.channels() > 1;
  const bool in_place = !swap || header.interlace_method != SPNG_INTERLACE_NONE;
  cv::Mat block;
  if (!in_place) block.create(std::min(kBlockRows, image.rows), image.cols, image.type());
  const int swap_code = image.channels() == 3 ? cv::COLOR_RGB2BGR : cv::COLOR_RGBA2BGRA;
  int status = SPNG_OK;
  while (status == SPNG_OK) {
    spng_row_info row{};
    check(spng_get_row_info(png, &row), "image data");
    const int y = static_cast<int>(row.row_num);
    status = spng_decode_row(png, in_place ? image.ptr(y) : block.ptr(y % kBlockRows), row_bytes);
    if (!in_place && (status == SPNG_OK || status == SPNG_EOI) &&
        (y % kBlockRows == kBlockRows - 1 || y == image.rows - 1)) {
      const int first = y - y % kBlockRows;
      cv::cvtColor(block.rowRange(0, y - first + 1), image.rowRange(first, y + 1), swap_code);
    }
  }
  if (status != SPNG_EOI) check(status, "image data");
  // The chunks after the image, up to IEND: a file cut short after its image data is refused too.
  check(spng_decode_chunks(png), "end of file");
  if (swap && in_place) cv::cvtColor(image.clone(), image, swap_code);
  return image;
}

}  // namespace oefmt::detail
