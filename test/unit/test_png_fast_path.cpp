// SPDX-License-Identifier: GPL-3.0-or-later
// The fast path for 8-bit RGB(A) PNGs (src/io/png_decoders.h), on files built chunk by chunk
// here: every row filter at every width gives the pixels that were written (and libspng's
// picture); anything it must not decide itself (other kinds, transparency, damaged or unusual
// structure) it gives back, and decodeImage then behaves exactly as libspng does.
#include <gtest/gtest.h>

#include <zlib.h>

#include <cstdint>
#include <cstdlib>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "io/png_decoders.h"
#include "oefmt/error.h"
#include "oefmt/io/image_decoding.h"

namespace oefmt {
namespace {

using Bytes = std::vector<std::uint8_t>;

void put32(Bytes& out, std::uint32_t v) {
  for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
}

struct Chunk {
  std::string type;
  Bytes body;
  bool bad_crc = false;
};

Bytes fileOf(const std::vector<Chunk>& chunks) {
  Bytes png = {137, 80, 78, 71, 13, 10, 26, 10};
  for (const Chunk& chunk : chunks) {
    put32(png, static_cast<std::uint32_t>(chunk.body.size()));
    const std::size_t start = png.size();
    png.insert(png.end(), chunk.type.begin(), chunk.type.end());
    png.insert(png.end(), chunk.body.begin(), chunk.body.end());
    const auto crc = static_cast<std::uint32_t>(crc32(0, png.data() + start, static_cast<uInt>(png.size() - start)));
    put32(png, chunk.bad_crc ? crc ^ 1u : crc);
  }
  return png;
}

Chunk header(std::uint32_t width, std::uint32_t height, int colour_type, int bit_depth = 8, int interlace = 0) {
  Chunk chunk{"IHDR", {}};
  put32(chunk.body, width);
  put32(chunk.body, height);
  chunk.body.insert(chunk.body.end(), {static_cast<std::uint8_t>(bit_depth), static_cast<std::uint8_t>(colour_type),
                                       0, 0, static_cast<std::uint8_t>(interlace)});
  return chunk;
}

Bytes deflate(const Bytes& raw) {
  uLongf size = compressBound(static_cast<uLong>(raw.size()));
  Bytes out(size);
  EXPECT_EQ(compress2(out.data(), &size, raw.data(), static_cast<uLong>(raw.size()), 6), Z_OK);
  out.resize(size);
  return out;
}

int paeth(int a, int b, int c) {
  const int pa = std::abs(b - c), pb = std::abs(a - c), pc = std::abs(a + b - 2 * c);
  return (pa <= pb && pa <= pc) ? a : (pb <= pc ? b : c);
}

// The PNG filtering of `image`'s rows (RGB or RGBA order), the filter of row y being filters(y):
// written from the PNG specification, independently of the decoder's unfiltering.
Bytes filterRows(const cv::Mat& image, const std::function<int(int)>& filters) {
  const int bpp = image.channels();
  const int bytes = image.cols * bpp;
  Bytes out;
  for (int y = 0; y < image.rows; ++y) {
    const std::uint8_t* row = image.ptr<std::uint8_t>(y);
    const std::uint8_t* up = y > 0 ? image.ptr<std::uint8_t>(y - 1) : nullptr;
    const int filter = filters(y);
    out.push_back(static_cast<std::uint8_t>(filter));
    for (int x = 0; x < bytes; ++x) {
      const int a = x >= bpp ? row[x - bpp] : 0, b = up ? up[x] : 0, c = (up && x >= bpp) ? up[x - bpp] : 0;
      const int predictor = filter == 1 ? a : filter == 2 ? b : filter == 3 ? (a + b) / 2 : filter == 4 ? paeth(a, b, c) : 0;
      out.push_back(static_cast<std::uint8_t>(row[x] - predictor));
    }
  }
  return out;
}

cv::Mat randomImage(int rows, int cols, int channels, int seed, bool smooth) {
  cv::Mat image(rows, cols, CV_8UC(channels));
  cv::RNG random(static_cast<std::uint64_t>(seed));
  random.fill(image, cv::RNG::UNIFORM, cv::Scalar::all(0), cv::Scalar::all(256));
  if (smooth) cv::GaussianBlur(image, image, cv::Size(5, 5), 2.0);
  return image;
}

// A well-formed file of `rgb` (RGB or RGBA order) with a text chunk before and after the image data.
std::vector<Chunk> chunksOf(const cv::Mat& rgb, const std::function<int(int)>& filters) {
  return {header(rgb.cols, rgb.rows, rgb.channels() == 3 ? 2 : 6),
          {"tEXt", {'S', 'o', 'f', 't', 'w', 'a', 'r', 'e', 0, 'x'}},
          {"IDAT", deflate(filterRows(rgb, filters))},
          {"tIME", {7, 234, 12, 2, 3, 4, 5}},
          {"IEND", {}}};
}

cv::Mat opencvOrder(const cv::Mat& rgb) {
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, rgb.channels() == 3 ? cv::COLOR_RGB2BGR : cv::COLOR_RGBA2BGRA);
  return bgr;
}

bool identical(const cv::Mat& a, const cv::Mat& b) {
  return a.type() == b.type() && a.size() == b.size() && cv::norm(a, b, cv::NORM_INF) == 0.0;
}

std::optional<cv::Mat> fast(const Bytes& png) { return detail::decodeColourPngFast(png.data(), png.size()); }

// decodeImage on a file the fast path gave back: exactly libspng's outcome, picture or error.
void expectLibspngOutcome(const Bytes& png, const std::string& what) {
  std::optional<cv::Mat> reference;
  std::string reference_error;
  try {
    reference = detail::decodePngLibspng(png.data(), png.size());
  } catch (const InputError& e) {
    reference_error = e.what();
  }
  try {
    const cv::Mat decoded = decodeImage(png.data(), png.size());
    ASSERT_TRUE(reference.has_value()) << what << ": decoded, libspng refuses: " << reference_error;
    EXPECT_TRUE(identical(*reference, decoded)) << what;
  } catch (const InputError& e) {
    EXPECT_FALSE(reference.has_value()) << what << ": refused (" << e.what() << "), libspng decodes it";
    EXPECT_EQ(reference_error, e.what()) << what;
  }
}

TEST(PngFastPath, EveryFilterAtEveryWidthGivesTheWrittenPixels) {
  // Widths 1-40: every remainder of the SIMD Sub steps (12 and 16 bytes) and rows shorter than one.
  std::vector<int> widths;
  for (int w = 1; w <= 40; ++w) widths.push_back(w);
  widths.push_back(512);
  int checked = 0;
  for (const int channels : {3, 4}) {
    for (const int width : widths) {
      for (int filter = 0; filter <= 5; ++filter) {  // 5: a different filter on every row
        const bool smooth = (width + filter) % 2 == 0;
        const cv::Mat rgb = randomImage(width == 512 ? 64 : 7, width, channels, 31 * width + filter, smooth);
        const auto filters = [filter](int y) { return filter == 5 ? (y * 3 + 1) % 5 : filter; };
        const Bytes png = fileOf(chunksOf(rgb, filters));
        const std::optional<cv::Mat> decoded = fast(png);
        ASSERT_TRUE(decoded.has_value()) << channels << " channels, width " << width << ", filter " << filter;
        ASSERT_TRUE(identical(opencvOrder(rgb), *decoded)) << channels << " channels, width " << width << ", filter " << filter;
        ASSERT_TRUE(identical(detail::decodePngLibspng(png.data(), png.size()), *decoded));
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 2 * 41 * 6);
}

TEST(PngFastPath, TakesImageDataSplitIntoManyChunks) {
  const cv::Mat rgb = randomImage(9, 21, 3, 5, true);
  const Bytes stream = deflate(filterRows(rgb, [](int y) { return y % 5; }));
  std::vector<Chunk> chunks = {header(21, 9, 2), {"IDAT", {}}};  // an empty one too
  for (const std::uint8_t byte : stream) chunks.push_back({"IDAT", {byte}});
  chunks.push_back({"IEND", {}});
  const Bytes png = fileOf(chunks);
  const std::optional<cv::Mat> decoded = fast(png);
  ASSERT_TRUE(decoded.has_value());
  EXPECT_TRUE(identical(opencvOrder(rgb), *decoded));
  EXPECT_TRUE(identical(cv::imdecode(png, cv::IMREAD_UNCHANGED), *decoded));
}

TEST(PngFastPath, GivesBackWhatLibspngMustDecide) {
  const cv::Mat rgb = randomImage(6, 10, 3, 8, false);
  const auto sub = [](int) { return 1; };
  const std::vector<Chunk> good = chunksOf(rgb, sub);
  ASSERT_TRUE(fast(fileOf(good)).has_value());
  const Bytes stream = good[2].body;
  const Bytes filtered = filterRows(rgb, sub);

  std::vector<std::pair<std::string, std::vector<Chunk>>> cases;
  const auto variant = [&](const std::string& what, const std::function<void(std::vector<Chunk>&)>& change) {
    std::vector<Chunk> chunks = good;
    change(chunks);
    cases.emplace_back(what, chunks);
  };
  // Other kinds (the same stream: libspng reads or refuses it by its own rules).
  variant("grey", [](auto& c) { c[0] = header(30, 6, 0); });
  variant("grey + alpha", [](auto& c) { c[0] = header(15, 6, 4); });
  variant("16-bit RGB", [](auto& c) { c[0] = header(5, 6, 2, 16); });
  variant("palette", [](auto& c) { c[0] = header(30, 6, 3); });
  variant("interlaced", [](auto& c) { c[0] = header(10, 6, 2, 8, 1); });
  variant("over the pixel limit", [](auto& c) { c[0] = header(1u << 14, 1u << 13, 2); });
  variant("bad compression method", [](auto& c) { c[0].body[10] = 1; });
  // Chunks that change the picture or the file's meaning.
  variant("transparency", [](auto& c) { c.insert(c.begin() + 1, Chunk{"tRNS", {0, 1, 0, 2, 0, 3}}); });
  variant("palette in RGB", [](auto& c) { c.insert(c.begin() + 1, Chunk{"PLTE", {1, 2, 3}}); });
  variant("second header", [&](auto& c) { c.insert(c.begin() + 1, header(10, 6, 2)); });
  variant("unknown critical chunk", [](auto& c) { c.insert(c.begin() + 1, Chunk{"ABCD", {1}}); });
  variant("chunk name not letters", [](auto& c) { c.insert(c.begin() + 1, Chunk{"ab1d", {1}}); });
  variant("image data split by a chunk", [&](auto& c) {
    c[2].body.assign(stream.begin(), stream.begin() + 10);
    c.insert(c.begin() + 3, Chunk{"tEXt", {'a', 0, 'b'}});
    c.insert(c.begin() + 4, Chunk{"IDAT", Bytes(stream.begin() + 10, stream.end())});
  });
  variant("no image data", [](auto& c) { c.erase(c.begin() + 2); });
  variant("no end", [](auto& c) { c.pop_back(); });
  variant("end with a body", [](auto& c) { c.back().body = {0}; });
  // Damaged checksums and streams.
  for (std::size_t i = 0; i < good.size(); ++i) {
    variant("bad CRC of chunk " + std::to_string(i), [i](auto& c) { c[i].bad_crc = true; });
  }
  variant("bad Adler-32", [](auto& c) { c[2].body.back() ^= 1; });
  variant("bytes after the stream", [](auto& c) { c[2].body.push_back(0); });
  variant("stream one row short", [&](auto& c) {
    c[2].body = deflate(Bytes(filtered.begin(), filtered.end() - (filtered.size() / 6)));
  });
  variant("stream one byte long", [&](auto& c) {
    Bytes longer = filtered;
    longer.push_back(0);
    c[2].body = deflate(longer);
  });
  variant("not a filter type", [&](auto& c) {
    Bytes bad = filtered;
    bad[bad.size() / 6 * 3] = 5;  // the fourth row's filter byte
    c[2].body = deflate(bad);
  });
  variant("not zlib", [](auto& c) { c[2].body.assign(40, 0xab); });

  for (const auto& [what, chunks] : cases) {
    const Bytes png = fileOf(chunks);
    EXPECT_FALSE(fast(png).has_value()) << what;
    expectLibspngOutcome(png, what);
  }
}

TEST(PngFastPath, DamagedOrCutFilesAreGivenBack) {
  const cv::Mat rgb = randomImage(12, 17, 4, 3, true);
  const Bytes png = fileOf(chunksOf(rgb, [](int y) { return y % 5; }));
  const cv::Mat original = opencvOrder(rgb);
  // A flipped bit anywhere after the signature: a CRC catches it (or it is in a CRC).
  for (std::size_t at = 8; at < png.size(); ++at) {
    Bytes damaged = png;
    damaged[at] ^= 0x04;
    const std::optional<cv::Mat> decoded = fast(damaged);
    EXPECT_FALSE(decoded.has_value()) << "bit flipped at byte " << at;
    expectLibspngOutcome(damaged, "bit flipped at byte " + std::to_string(at));
  }
  for (std::size_t length = 0; length < png.size(); ++length) {
    EXPECT_FALSE(fast(Bytes(png.begin(), png.begin() + length)).has_value()) << "cut at " << length;
  }
  EXPECT_TRUE(identical(original, *fast(png)));
  Bytes trailing = png;  // bytes after IEND are no part of the file
  trailing.insert(trailing.end(), {1, 2, 3});
  ASSERT_TRUE(fast(trailing).has_value());
  EXPECT_TRUE(identical(original, *fast(trailing)));
}

TEST(PngFastPath, ServesDecodeImageForOpenCvsColourFiles) {
  for (const int type : {CV_8UC3, CV_8UC4}) {
    const cv::Mat image = randomImage(33, 47, CV_MAT_CN(type), type, true);
    for (int level = 0; level <= 9; level += 3) {
      Bytes png;
      ASSERT_TRUE(cv::imencode(".png", image, png, {cv::IMWRITE_PNG_COMPRESSION, level}));
      ASSERT_TRUE(fast(png).has_value()) << "OpenCV's writer, level " << level;
      EXPECT_TRUE(identical(image, decodeImage(png.data(), png.size())));
    }
  }
}

}  // namespace
}  // namespace oefmt
