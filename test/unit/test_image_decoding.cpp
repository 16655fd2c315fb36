// SPDX-License-Identifier: GPL-3.0-or-later
// The fast PNG decoder against OpenCV's: identical pixels for every layout it takes (all five
// row filters, 8/16 bit, grey/RGB/RGBA, split IDAT chunks, OpenCV's own writer), OpenCV for the
// rest, and damaged files refused without a crash.
#include <gtest/gtest.h>

#include <libdeflate.h>

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"
#include "oefmt/io/image_decoding.h"

namespace oefmt {
namespace {

using Bytes = std::vector<std::uint8_t>;

void put32(Bytes& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}

void putChunk(Bytes& out, const char* type, const Bytes& body) {
  put32(out, static_cast<std::uint32_t>(body.size()));
  Bytes typed(type, type + 4);
  typed.insert(typed.end(), body.begin(), body.end());
  out.insert(out.end(), typed.begin(), typed.end());
  put32(out, libdeflate_crc32(0, typed.data(), typed.size()));
}

int paeth(int a, int b, int c) {
  const int pa = std::abs(b - c), pb = std::abs(a - c), pc = std::abs(a + b - 2 * c);
  return (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
}

struct PngOptions {
  int colour_type = -1;      ///< -1: from the image's channels
  std::size_t idat_split = 0;  ///< > 0: IDAT chunks of at most this many bytes
  bool add_trns = false;
  bool add_text = true;      ///< an ancillary chunk to skip
};

// A minimal PNG writer with row y filtered by filter type y % 5 (OpenCV's writer picks filters
// itself), so every unfilter path is exercised.
Bytes encodePng(const cv::Mat& image, const PngOptions& options = {}) {
  const int channels = image.channels();
  const bool sixteen = image.depth() == CV_16U;
  const int bpp = channels * (sixteen ? 2 : 1);
  const std::size_t row_bytes = static_cast<std::size_t>(image.cols) * bpp;
  std::vector<Bytes> rows(image.rows, Bytes(row_bytes));
  for (int y = 0; y < image.rows; ++y) {
    for (int x = 0; x < image.cols; ++x) {
      for (int c = 0; c < channels; ++c) {
        // PNG order is RGB(A); OpenCV's is BGR(A).
        const int source = (channels >= 3 && c < 3) ? 2 - c : c;
        const std::size_t at = (static_cast<std::size_t>(x) * channels + c) * (sixteen ? 2 : 1);
        if (sixteen) {
          const std::uint16_t v = image.ptr<std::uint16_t>(y)[x * channels + source];
          rows[y][at] = static_cast<std::uint8_t>(v >> 8);
          rows[y][at + 1] = static_cast<std::uint8_t>(v & 0xff);
        } else {
          rows[y][at] = image.ptr<std::uint8_t>(y)[x * channels + source];
        }
      }
    }
  }
  Bytes filtered;
  const Bytes zeros(row_bytes, 0);
  for (int y = 0; y < image.rows; ++y) {
    const int type = y % 5;
    const Bytes& row = rows[y];
    const Bytes& up = y > 0 ? rows[y - 1] : zeros;
    filtered.push_back(static_cast<std::uint8_t>(type));
    for (std::size_t x = 0; x < row_bytes; ++x) {
      const int a = x >= static_cast<std::size_t>(bpp) ? row[x - bpp] : 0;
      const int b = up[x];
      const int c = x >= static_cast<std::size_t>(bpp) ? up[x - bpp] : 0;
      const int predictor = type == 0 ? 0 : type == 1 ? a : type == 2 ? b : type == 3 ? (a + b) / 2 : paeth(a, b, c);
      filtered.push_back(static_cast<std::uint8_t>(row[x] - predictor));
    }
  }
  libdeflate_compressor* compressor = libdeflate_alloc_compressor(6);
  Bytes compressed(libdeflate_zlib_compress_bound(compressor, filtered.size()));
  compressed.resize(libdeflate_zlib_compress(compressor, filtered.data(), filtered.size(),
                                             compressed.data(), compressed.size()));
  libdeflate_free_compressor(compressor);

  Bytes png = {137, 80, 78, 71, 13, 10, 26, 10};
  Bytes header;
  put32(header, static_cast<std::uint32_t>(image.cols));
  put32(header, static_cast<std::uint32_t>(image.rows));
  const int colour = options.colour_type >= 0 ? options.colour_type : (channels == 1 ? 0 : channels == 3 ? 2 : 6);
  header.insert(header.end(), {static_cast<std::uint8_t>(sixteen ? 16 : 8), static_cast<std::uint8_t>(colour), 0, 0, 0});
  putChunk(png, "IHDR", header);
  if (options.add_text) putChunk(png, "tEXt", Bytes{'k', 0, 'v'});
  if (options.add_trns) putChunk(png, "tRNS", Bytes(channels == 1 ? 2 : 6, 0));
  const std::size_t split = options.idat_split > 0 ? options.idat_split : compressed.size();
  for (std::size_t at = 0; at < compressed.size(); at += split) {
    putChunk(png, "IDAT", Bytes(compressed.begin() + at, compressed.begin() + std::min(compressed.size(), at + split)));
  }
  putChunk(png, "IEND", {});
  return png;
}

cv::Mat noise(int rows, int cols, int type, int seed) {
  cv::Mat image(rows, cols, type);
  cv::RNG random(static_cast<std::uint64_t>(seed));
  const double top = CV_MAT_DEPTH(type) == CV_16U ? 65536.0 : 256.0;
  random.fill(image, cv::RNG::UNIFORM, cv::Scalar::all(0), cv::Scalar::all(top));
  return image;
}

cv::Mat openCvDecode(const Bytes& bytes) {
  try {
    return cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception&) {
    return cv::Mat();
  }
}

void expectIdentical(const cv::Mat& expected, const cv::Mat& got) {
  ASSERT_FALSE(got.empty());
  ASSERT_EQ(expected.type(), got.type());
  ASSERT_EQ(expected.size(), got.size());
  EXPECT_EQ(cv::norm(expected, got, cv::NORM_INF), 0.0);
}

class FastPngLayouts : public ::testing::TestWithParam<int> {};

TEST_P(FastPngLayouts, EveryFilterGivesOpenCvsPixels) {
  const int type = GetParam();
  // Odd sizes: no row is a multiple of a vector width.
  const cv::Mat image = noise(23, 37, type, type + 1);
  PngOptions options;
  options.idat_split = 97;  // many IDAT chunks: the stream is split mid-symbol
  const Bytes png = encodePng(image, options);
  const std::optional<cv::Mat> fast = decodePngFast(png.data(), png.size());
  ASSERT_TRUE(fast.has_value()) << "the fast path must take this layout";
  expectIdentical(image, *fast);
  expectIdentical(openCvDecode(png), *fast);
  expectIdentical(image, decodeImage(png.data(), png.size()));
}

INSTANTIATE_TEST_SUITE_P(DepthsAndChannels, FastPngLayouts,
                         ::testing::Values(CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1, CV_16UC3, CV_16UC4));

TEST(FastPng, NarrowRowsUnfilterExactly) {
  // Rows of one pixel and a few: the filters' left neighbour falls outside the row at first.
  for (const int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1, CV_16UC3, CV_16UC4}) {
    for (int width = 1; width <= 12; ++width) {
      const cv::Mat image = noise(6, width, type, 100 * type + width);
      const Bytes png = encodePng(image);
      const std::optional<cv::Mat> fast = decodePngFast(png.data(), png.size());
      ASSERT_TRUE(fast.has_value()) << "type " << type << " width " << width;
      expectIdentical(image, *fast);
    }
  }
}

TEST(FastPng, OpenCvsOwnWriterAtEveryCompressionLevel) {
  const cv::Mat image = noise(64, 80, CV_8UC3, 7);
  cv::Mat smooth;
  cv::GaussianBlur(image, smooth, cv::Size(9, 9), 3.0);  // makes the writer choose varied filters
  for (int level = 0; level <= 9; level += 3) {
    Bytes png;
    ASSERT_TRUE(cv::imencode(".png", smooth, png, {cv::IMWRITE_PNG_COMPRESSION, level}));
    const std::optional<cv::Mat> fast = decodePngFast(png.data(), png.size());
    ASSERT_TRUE(fast.has_value()) << "level " << level;
    expectIdentical(smooth, *fast);
  }
}

TEST(FastPng, LayoutsItDoesNotTakeGoToOpenCv) {
  const cv::Mat grey = noise(16, 16, CV_8UC1, 3);
  PngOptions transparent;
  transparent.add_trns = true;
  const Bytes with_trns = encodePng(grey, transparent);
  EXPECT_FALSE(decodePngFast(with_trns.data(), with_trns.size()).has_value());
  expectIdentical(openCvDecode(with_trns), decodeImage(with_trns.data(), with_trns.size()));

  // Grey + alpha (colour type 4): OpenCV converts it; so does decodeImage, through OpenCV.
  PngOptions grey_alpha;
  grey_alpha.colour_type = 4;
  const Bytes two_channel = encodePng(noise(16, 16, CV_8UC2, 4), grey_alpha);
  EXPECT_FALSE(decodePngFast(two_channel.data(), two_channel.size()).has_value());
  expectIdentical(openCvDecode(two_channel), decodeImage(two_channel.data(), two_channel.size()));

  Bytes jpeg;
  ASSERT_TRUE(cv::imencode(".jpg", noise(32, 32, CV_8UC3, 5), jpeg));
  EXPECT_FALSE(decodePngFast(jpeg.data(), jpeg.size()).has_value());
  expectIdentical(openCvDecode(jpeg), decodeImage(jpeg.data(), jpeg.size()));
}

TEST(FastPng, DamagedFilesAreRefusedNotMisread) {
  const cv::Mat image = noise(40, 40, CV_8UC3, 9);
  const Bytes png = encodePng(image);
  // A flipped bit anywhere after the signature: a CRC or zlib check fails, or (in the tEXt
  // chunk's CRC-checked body) the file is refused; never a different picture from the fast path.
  for (std::size_t at = 8; at < png.size(); at += 7) {
    Bytes damaged = png;
    damaged[at] ^= 0x10;
    const std::optional<cv::Mat> fast = decodePngFast(damaged.data(), damaged.size());
    EXPECT_FALSE(fast.has_value()) << "bit flip at byte " << at << " was not noticed";
    EXPECT_NO_THROW(decodeImage(damaged.data(), damaged.size())) << at;
  }
  for (std::size_t length = 0; length < png.size(); length += 13) {
    const Bytes truncated(png.begin(), png.begin() + length);
    EXPECT_FALSE(decodePngFast(truncated.data(), truncated.size()).has_value()) << length;
    const cv::Mat decoded = decodeImage(truncated.data(), truncated.size());
    EXPECT_TRUE(decoded.empty() || decoded.size() == image.size()) << length;
  }
  EXPECT_TRUE(decodeImage(nullptr, 0).empty());
}

TEST(FastPng, HugeHeaderIsAClearError) {
  Bytes png = {137, 80, 78, 71, 13, 10, 26, 10};
  Bytes header;
  put32(header, 100000);
  put32(header, 100000);
  header.insert(header.end(), {8, 2, 0, 0, 0});
  putChunk(png, "IHDR", header);
  putChunk(png, "IEND", {});
  EXPECT_FALSE(decodePngFast(png.data(), png.size()).has_value());
  try {
    decodeImage(png.data(), png.size());
    FAIL() << "a 10-gigapixel header was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("100000x100000"), std::string::npos) << e.what();
  }
}

// Found by fuzz_image: a header of 3623878655 x 4294916655 overflowed the pixel count.
TEST(FastPng, HeaderSidesNearTwoToThe32AreAClearError) {
  Bytes png = {137, 80, 78, 71, 13, 10, 26, 10};
  Bytes header;
  put32(header, 0xd7ffffffu);
  put32(header, 0xffff3a2fu);
  header.insert(header.end(), {8, 2, 0, 0, 0});
  putChunk(png, "IHDR", header);
  putChunk(png, "IEND", {});
  EXPECT_FALSE(decodePngFast(png.data(), png.size()).has_value());
  EXPECT_THROW(decodeImage(png.data(), png.size()), InputError);
}

TEST(FastPng, ReadImageFileMissingOrEmptyGivesEmpty) {
  EXPECT_TRUE(readImageFile("/nonexistent/oefmt/image.png").empty());
  EXPECT_TRUE(readImageFile("/dev/null").empty());
}

}  // namespace
}  // namespace oefmt
