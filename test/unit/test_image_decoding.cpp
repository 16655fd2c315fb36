// SPDX-License-Identifier: GPL-3.0-or-later
// decodeImage against OpenCV's own codecs: the same picture (type, size, every sample) for every
// kind of PNG (grey of 1 to 16 bits, grey + alpha, RGB, RGBA, palettes, transparency, interlacing,
// each row filter) and for other formats; damaged, truncated and oversized files refused with an
// InputError that says why, never a crash or a different picture.
#include <gtest/gtest.h>

#include <spng.h>
#include <zlib.h>

#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "support/temp_dir.h"
#include "oefmt/error.h"
#include "oefmt/io/image_decoding.h"

namespace oefmt {
namespace {

using Bytes = std::vector<std::uint8_t>;

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
  ASSERT_FALSE(expected.empty());
  ASSERT_FALSE(got.empty());
  ASSERT_EQ(cv::typeToString(expected.type()), cv::typeToString(got.type()));
  ASSERT_EQ(expected.size(), got.size());
  EXPECT_EQ(cv::norm(expected, got, cv::NORM_INF), 0.0);
}

std::string errorOf(const Bytes& bytes) {
  try {
    decodeImage(bytes.data(), bytes.size());
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// A PNG written by libspng (the writer OpenCV lacks for palettes, grey + alpha, bit depths below
// 8, transparency and interlacing). `samples` are the rows in the PNG's own layout (packed below 8
// bits, host-endian 16-bit samples).
struct PngSpec {
  int width = 23, height = 19;  // odd: no row is a multiple of a vector width
  int bit_depth = 8;
  int colour_type = SPNG_COLOR_TYPE_TRUECOLOR;
  bool interlaced = false;
  int filter_choice = SPNG_FILTER_CHOICE_ALL;
  std::vector<std::uint8_t> samples;
  std::vector<spng_plte_entry> palette;
  bool has_trns = false;
  spng_trns trns{};
};

int channelsOf(int colour_type) {
  switch (colour_type) {
    case SPNG_COLOR_TYPE_TRUECOLOR: return 3;
    case SPNG_COLOR_TYPE_GRAYSCALE_ALPHA: return 2;
    case SPNG_COLOR_TYPE_TRUECOLOR_ALPHA: return 4;
    default: return 1;
  }
}

std::size_t rowBytes(const PngSpec& spec) {
  return (static_cast<std::size_t>(spec.width) * channelsOf(spec.colour_type) * spec.bit_depth + 7) / 8;
}

Bytes writePng(const PngSpec& spec) {
  std::unique_ptr<spng_ctx, void (*)(spng_ctx*)> context(spng_ctx_new(SPNG_CTX_ENCODER), &spng_ctx_free);
  spng_ctx* png = context.get();
  EXPECT_EQ(spng_set_option(png, SPNG_ENCODE_TO_BUFFER, 1), 0);
  EXPECT_EQ(spng_set_option(png, SPNG_FILTER_CHOICE, spec.filter_choice), 0);
  spng_ihdr header{};
  header.width = static_cast<std::uint32_t>(spec.width);
  header.height = static_cast<std::uint32_t>(spec.height);
  header.bit_depth = static_cast<std::uint8_t>(spec.bit_depth);
  header.color_type = static_cast<std::uint8_t>(spec.colour_type);
  header.interlace_method = spec.interlaced ? SPNG_INTERLACE_ADAM7 : SPNG_INTERLACE_NONE;
  EXPECT_EQ(spng_set_ihdr(png, &header), 0);
  if (!spec.palette.empty()) {
    spng_plte palette{};
    palette.n_entries = static_cast<std::uint32_t>(spec.palette.size());
    for (std::size_t i = 0; i < spec.palette.size(); ++i) palette.entries[i] = spec.palette[i];
    EXPECT_EQ(spng_set_plte(png, &palette), 0);
  }
  spng_trns trns = spec.trns;
  if (spec.has_trns) {
    EXPECT_EQ(spng_set_trns(png, &trns), 0);
  }
  char keyword[] = "Software", text[] = "oefmt test";
  spng_text comment{};
  std::snprintf(comment.keyword, sizeof(comment.keyword), "%s", keyword);
  comment.type = SPNG_TEXT;
  comment.length = sizeof(text) - 1;
  comment.text = text;
  EXPECT_EQ(spng_set_text(png, &comment, 1), 0);  // an ancillary chunk before the image
  EXPECT_EQ(spng_encode_image(png, spec.samples.data(), spec.samples.size(), SPNG_FMT_PNG,
                              SPNG_ENCODE_FINALIZE),
            0);
  std::size_t size = 0;
  int error = 0;
  void* buffer = spng_get_png_buffer(png, &size, &error);
  EXPECT_EQ(error, 0);
  Bytes bytes(static_cast<std::uint8_t*>(buffer), static_cast<std::uint8_t*>(buffer) + size);
  std::free(buffer);
  return bytes;
}

// Samples from a small set whose two bytes are equal (so the same in either byte order): the
// transparent colour of a tRNS chunk then occurs often.
void fillFewValues(PngSpec& spec, int seed) {
  spec.samples.resize(rowBytes(spec) * spec.height);
  cv::RNG random(static_cast<std::uint64_t>(seed));
  if (spec.bit_depth < 8 || spec.colour_type == SPNG_COLOR_TYPE_INDEXED) {
    for (std::uint8_t& byte : spec.samples) byte = static_cast<std::uint8_t>(random.uniform(0, 256));
    return;
  }
  for (std::uint8_t& byte : spec.samples) byte = random.uniform(0, 2) == 0 ? 0x12 : 0xee;
  if (spec.bit_depth == 16) {
    for (std::size_t i = 0; i + 1 < spec.samples.size(); i += 2) spec.samples[i + 1] = spec.samples[i];
  }
}

struct Kind {
  const char* name;
  int colour_type;
  int bit_depth;
  bool trns;
  int expected_type;  // what cv::imdecode(IMREAD_UNCHANGED) gives
};

PngSpec specFor(const Kind& kind, int seed) {
  PngSpec spec;
  spec.colour_type = kind.colour_type;
  spec.bit_depth = kind.bit_depth;
  cv::RNG random(static_cast<std::uint64_t>(seed));
  if (kind.colour_type == SPNG_COLOR_TYPE_INDEXED) {
    spec.palette.resize(std::size_t{1} << kind.bit_depth);  // every index valid
    for (spng_plte_entry& entry : spec.palette) {
      entry.red = static_cast<std::uint8_t>(random.uniform(0, 256));
      entry.green = static_cast<std::uint8_t>(random.uniform(0, 256));
      entry.blue = static_cast<std::uint8_t>(random.uniform(0, 256));
    }
  }
  fillFewValues(spec, seed);
  if (kind.trns) {
    spec.has_trns = true;
    const std::uint16_t low = kind.bit_depth == 16 ? 0x1212 : kind.bit_depth == 8 ? 0x12 : 1;
    const std::uint16_t high = kind.bit_depth == 16 ? 0xeeee : kind.bit_depth == 8 ? 0xee : 0;
    spec.trns.gray = low;
    spec.trns.red = low;
    spec.trns.green = high;
    spec.trns.blue = low;
    spec.trns.n_type3_entries = 3;  // fewer than the palette: the rest are opaque
    spec.trns.type3_alpha[0] = 0;
    spec.trns.type3_alpha[1] = 100;
    spec.trns.type3_alpha[2] = 255;
  }
  return spec;
}

const Kind kKinds[] = {
    {"grey1", SPNG_COLOR_TYPE_GRAYSCALE, 1, false, CV_8UC1},
    {"grey2", SPNG_COLOR_TYPE_GRAYSCALE, 2, false, CV_8UC1},
    {"grey4", SPNG_COLOR_TYPE_GRAYSCALE, 4, false, CV_8UC1},
    {"grey8", SPNG_COLOR_TYPE_GRAYSCALE, 8, false, CV_8UC1},
    {"grey16", SPNG_COLOR_TYPE_GRAYSCALE, 16, false, CV_16UC1},
    {"grey8_trns", SPNG_COLOR_TYPE_GRAYSCALE, 8, true, CV_8UC1},
    {"grey16_trns", SPNG_COLOR_TYPE_GRAYSCALE, 16, true, CV_16UC1},
    {"grey_alpha8", SPNG_COLOR_TYPE_GRAYSCALE_ALPHA, 8, false, CV_8UC4},
    {"grey_alpha16", SPNG_COLOR_TYPE_GRAYSCALE_ALPHA, 16, false, CV_16UC4},
    {"rgb8", SPNG_COLOR_TYPE_TRUECOLOR, 8, false, CV_8UC3},
    {"rgb16", SPNG_COLOR_TYPE_TRUECOLOR, 16, false, CV_16UC3},
    {"rgb8_trns", SPNG_COLOR_TYPE_TRUECOLOR, 8, true, CV_8UC4},
    {"rgb16_trns", SPNG_COLOR_TYPE_TRUECOLOR, 16, true, CV_16UC4},
    {"rgba8", SPNG_COLOR_TYPE_TRUECOLOR_ALPHA, 8, false, CV_8UC4},
    {"rgba16", SPNG_COLOR_TYPE_TRUECOLOR_ALPHA, 16, false, CV_16UC4},
    {"palette1", SPNG_COLOR_TYPE_INDEXED, 1, false, CV_8UC3},
    {"palette2", SPNG_COLOR_TYPE_INDEXED, 2, false, CV_8UC3},
    {"palette4", SPNG_COLOR_TYPE_INDEXED, 4, false, CV_8UC3},
    {"palette8", SPNG_COLOR_TYPE_INDEXED, 8, false, CV_8UC3},
    {"palette4_trns", SPNG_COLOR_TYPE_INDEXED, 4, true, CV_8UC4},
    {"palette8_trns", SPNG_COLOR_TYPE_INDEXED, 8, true, CV_8UC4},
};

class PngKinds : public ::testing::TestWithParam<Kind> {};

TEST_P(PngKinds, GiveOpenCvsPictureInterlacedOrNot) {
  const Kind kind = GetParam();
  for (const bool interlaced : {false, true}) {
    PngSpec spec = specFor(kind, kind.colour_type * 100 + kind.bit_depth);
    spec.interlaced = interlaced;
    const Bytes png = writePng(spec);
    const cv::Mat reference = openCvDecode(png);
    ASSERT_EQ(cv::typeToString(reference.type()), cv::typeToString(kind.expected_type)) << "OpenCV's own layout";
    const cv::Mat decoded = decodeImage(png.data(), png.size());
    expectIdentical(reference, decoded);
    if (kind.trns && decoded.channels() == 4) {
      // The tRNS chunk was applied: some pixels are (partly) transparent.
      cv::Mat alpha;
      cv::extractChannel(decoded, alpha, 3);
      double lowest = 0.0;
      cv::minMaxLoc(alpha, &lowest);
      EXPECT_EQ(lowest, 0.0) << kind.name;
    }
  }
}

INSTANTIATE_TEST_SUITE_P(EveryKind, PngKinds, ::testing::ValuesIn(kKinds),
                         [](const ::testing::TestParamInfo<Kind>& info) { return info.param.name; });

TEST(PngDecoding, EveryRowFilterGivesTheSamePicture) {
  for (const int filter : {SPNG_DISABLE_FILTERING, SPNG_FILTER_CHOICE_NONE, SPNG_FILTER_CHOICE_SUB,
                           SPNG_FILTER_CHOICE_UP, SPNG_FILTER_CHOICE_AVG, SPNG_FILTER_CHOICE_PAETH}) {
    for (const Kind& kind : {kKinds[3], kKinds[4], kKinds[9], kKinds[10], kKinds[13], kKinds[14]}) {
      PngSpec spec = specFor(kind, filter + kind.bit_depth);
      cv::RNG random(static_cast<std::uint64_t>(filter));
      for (std::uint8_t& byte : spec.samples) byte = static_cast<std::uint8_t>(random.uniform(0, 256));
      spec.filter_choice = filter;
      const Bytes png = writePng(spec);
      expectIdentical(openCvDecode(png), decodeImage(png.data(), png.size()));
    }
  }
}

TEST(PngDecoding, OpenCvsOwnWriterRoundTrips) {
  for (const int type : {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1, CV_16UC3, CV_16UC4}) {
    for (const int width : {1, 2, 5, 37}) {
      const cv::Mat image = noise(7, width, type, 100 * type + width);
      Bytes png;
      ASSERT_TRUE(cv::imencode(".png", image, png));
      expectIdentical(image, decodeImage(png.data(), png.size()));
    }
  }
  // Smooth content makes the writer choose varied filters; every compression level.
  cv::Mat smooth;
  cv::GaussianBlur(noise(64, 80, CV_8UC3, 7), smooth, cv::Size(9, 9), 3.0);
  for (int level = 0; level <= 9; level += 3) {
    Bytes png;
    ASSERT_TRUE(cv::imencode(".png", smooth, png, {cv::IMWRITE_PNG_COMPRESSION, level}));
    expectIdentical(smooth, decodeImage(png.data(), png.size()));
  }
}

TEST(ImageDecoding, OtherFormatsGoToOpenCv) {
  for (const char* extension : {".jpg", ".bmp", ".tiff", ".pgm"}) {
    const cv::Mat image = noise(32, 40, std::string(extension) == ".pgm" ? CV_8UC1 : CV_8UC3, 5);
    Bytes bytes;
    ASSERT_TRUE(cv::imencode(extension, image, bytes)) << extension;
    expectIdentical(openCvDecode(bytes), decodeImage(bytes.data(), bytes.size()));
  }
}

TEST(ImageDecoding, DamagedPngIsAnErrorOrTheSamePicture) {
  const cv::Mat image = noise(40, 40, CV_8UC3, 9);
  PngSpec spec;
  spec.width = spec.height = 40;
  spec.samples.assign(image.data, image.data + image.total() * image.elemSize());
  const Bytes png = writePng(spec);
  const cv::Mat original = decodeImage(png.data(), png.size());
  // A flipped bit anywhere after the signature: a CRC or zlib check fails (an InputError), or
  // it was in the tEXt chunk, which is then dropped (the same picture, as OpenCV does).
  int refused = 0;
  for (std::size_t at = 8; at < png.size(); at += 7) {
    Bytes damaged = png;
    damaged[at] ^= 0x10;
    try {
      expectIdentical(original, decodeImage(damaged.data(), damaged.size()));
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("PNG"), std::string::npos) << e.what();
      ++refused;
    }
  }
  EXPECT_GT(refused, 0);
  // Cut anywhere before the last chunk's CRC: refused. (libspng stops at IEND's header: a file
  // missing only IEND's constant CRC still has its whole picture, CRC- and zlib-checked.)
  for (std::size_t length = 1; length < png.size() - 4; length += 3) {
    const Bytes truncated(png.begin(), png.begin() + length);
    EXPECT_FALSE(errorOf(truncated).empty()) << "cut at " << length << " of " << png.size();
  }
}

void putChunk(Bytes& out, const char* type, const Bytes& body) {
  const auto put32 = [&out](std::uint32_t v) {
    for (int shift = 24; shift >= 0; shift -= 8) out.push_back(static_cast<std::uint8_t>(v >> shift));
  };
  put32(static_cast<std::uint32_t>(body.size()));
  const std::size_t start = out.size();
  out.insert(out.end(), type, type + 4);
  out.insert(out.end(), body.begin(), body.end());
  put32(static_cast<std::uint32_t>(crc32(0, out.data() + start, static_cast<uInt>(out.size() - start))));
}

Bytes pngWithHeader(std::uint32_t width, std::uint32_t height, const Bytes& idat) {
  Bytes png = {137, 80, 78, 71, 13, 10, 26, 10};
  Bytes header;
  for (const std::uint32_t v : {width, height}) {
    for (int shift = 24; shift >= 0; shift -= 8) header.push_back(static_cast<std::uint8_t>(v >> shift));
  }
  header.insert(header.end(), {8, 0, 0, 0, 0});  // 8-bit grey
  putChunk(png, "IHDR", header);
  if (!idat.empty()) putChunk(png, "IDAT", idat);
  putChunk(png, "IEND", {});
  return png;
}

TEST(ImageDecoding, ErrorsSayWhy) {
  EXPECT_THROW(decodeImage(nullptr, 0), InputError);
  const Bytes text = {'n', 'o', 't', ' ', 'a', 'n', ' ', 'i', 'm', 'a', 'g', 'e'};
  EXPECT_NE(errorOf(text).find("not an image"), std::string::npos) << errorOf(text);

  // Headers over the pixel limit, and sides near 2^32 (whose product once overflowed).
  EXPECT_NE(errorOf(pngWithHeader(100000, 100000, {})).find("100000x100000"), std::string::npos)
      << errorOf(pngWithHeader(100000, 100000, {}));
  EXPECT_NE(errorOf(pngWithHeader(0xd7ffffffu, 0xffff3a2fu, {})).find("PNG"), std::string::npos);
  EXPECT_NE(errorOf(pngWithHeader(0, 4, {})).find("PNG"), std::string::npos);

  // Valid chunks around a stream that is not zlib, or too short for the image.
  EXPECT_NE(errorOf(pngWithHeader(4, 4, Bytes(30, 0xab))).find("PNG"), std::string::npos);
  const Bytes row = {0, 1, 2, 3, 4};  // filter byte + 4 samples: one row of four
  Bytes deflated(compressBound(row.size()));
  uLongf deflated_size = deflated.size();
  ASSERT_EQ(compress(deflated.data(), &deflated_size, row.data(), row.size()), Z_OK);
  deflated.resize(deflated_size);
  const Bytes one_row = pngWithHeader(4, 1, deflated);
  EXPECT_EQ(decodeImage(one_row.data(), one_row.size()).at<std::uint8_t>(0, 3), 4);
  EXPECT_NE(errorOf(pngWithHeader(4, 4, deflated)).find("PNG"), std::string::npos);

  // An unknown critical chunk (upper case first letter) cannot be skipped.
  Bytes unknown(one_row.begin(), one_row.begin() + 8 + 25);  // signature, IHDR
  putChunk(unknown, "ABCD", {1, 2, 3});
  unknown.insert(unknown.end(), one_row.begin() + 8 + 25, one_row.end());
  EXPECT_NE(errorOf(unknown).find("PNG"), std::string::npos);
}

TEST(ImageDecoding, ReadImageFileNamesTheFile) {
  test::TempDir dir;
  const auto expectError = [](const std::string& path, const std::string& reason) {
    try {
      readImageFile(path);
      ADD_FAILURE() << path << " was read";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("'" + path + "'"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(reason), std::string::npos) << e.what();
    }
  };
  expectError("/nonexistent/oefmt/image.png", "no such file");
  expectError("/dev/null", "empty file");
  const std::string cut = dir / "cut.png";
  Bytes png;
  ASSERT_TRUE(cv::imencode(".png", noise(16, 16, CV_8UC1, 3), png));
  std::ofstream(cut, std::ios::binary).write(reinterpret_cast<const char*>(png.data()), 60);
  expectError(cut, "PNG");
  const std::string good = dir / "good.png";
  std::ofstream(good, std::ios::binary)
      .write(reinterpret_cast<const char*>(png.data()), static_cast<std::streamsize>(png.size()));
  expectIdentical(openCvDecode(png), readImageFile(good));
}

}  // namespace
}  // namespace oefmt
