// SPDX-License-Identifier: GPL-3.0-or-later
// Arbitrary bytes as a camera image -> prepareImage and Registrar::analyse. Inputs that start
// like a PNG or JPEG file go through oefmt::decodeImage first (the dataset folders' path: the
// fast path or libspng for PNGs), and where cv::imdecode (libpng for PNGs) also decodes them, the
// pictures must be identical, as must the fast path's and libspng's wherever both decode; anything else is read as a raw image: a header byte picks the pixel type, two more
// the size, and the rest are the pixels (float types take the bytes as bit patterns: NaN, inf,
// denormals).
#include <cmath>
#include <cstdint>
#include <cstring>
#include <optional>
#include <vector>

#include <fuzzer/FuzzedDataProvider.h>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "fuzz_check.h"
#include "io/png_decoders.h"
#include "oefmt/error.h"
#include "oefmt/io/image_decoding.h"
#include "oefmt/registration/image_prep.h"
#include "oefmt/registration/registration.h"

namespace {

using oefmt_fuzz::kSize;
using oefmt_fuzz::registrar;

bool looksCompressed(const uint8_t* data, size_t size) {
  static const uint8_t kPng[] = {0x89, 'P', 'N', 'G'};
  static const uint8_t kJpeg[] = {0xFF, 0xD8, 0xFF};
  return (size >= sizeof(kPng) && std::memcmp(data, kPng, sizeof(kPng)) == 0) ||
         (size >= sizeof(kJpeg) && std::memcmp(data, kJpeg, sizeof(kJpeg)) == 0);
}

cv::Mat rawImage(FuzzedDataProvider& input) {
  static const int kTypes[] = {CV_8UC1, CV_8UC3, CV_8UC4, CV_16UC1, CV_32FC1, CV_64FC1};
  const int type = input.PickValueInArray(kTypes);
  const int cols = input.ConsumeIntegralInRange(1, 300);
  const int rows = input.ConsumeIntegralInRange(1, 300);
  cv::Mat image(rows, cols, type, cv::Scalar::all(0));
  // The pixel bytes repeat when the input is short, so small inputs still give textured images.
  const std::vector<uint8_t> pixels = input.ConsumeRemainingBytes<uint8_t>();
  if (!pixels.empty()) {
    const size_t row_bytes = image.cols * image.elemSize();
    size_t k = 0;
    for (int r = 0; r < rows; ++r) {
      uint8_t* row = image.ptr<uint8_t>(r);
      for (size_t b = 0; b < row_bytes; ++b, ++k) row[b] = pixels[k % pixels.size()];
    }
  }
  return image;
}

void checkPrepared(const oefmt::PreparedImage& prepared, const cv::Mat& image) {
  using namespace oefmt_fuzz;
  check(prepared.grey.rows == kSize && prepared.grey.cols == kSize, "prepared size");
  checkFinite(prepared.grey, "prepared grey finite");
  checkFinite(prepared.texture, "prepared texture finite");
  check(prepared.texture >= 0.0, "prepared texture >= 0", prepared.texture);
  checkFinite(prepared.mean, "prepared mean finite");
  checkFinite(prepared.largest_magnitude, "prepared largest |value| finite");
  check(prepared.largest_magnitude >= std::abs(prepared.mean) * (1.0 - 1e-6),
        "largest |value| >= |mean|", prepared.largest_magnitude);
  check(prepared.invalid_pixels >= 0 &&
            static_cast<size_t>(prepared.invalid_pixels) <= image.total(),
        "invalid pixel count in range", prepared.invalid_pixels);
}

void checkSpectra(const oefmt::FrameSpectra& spectra) {
  using namespace oefmt_fuzz;
  checkFinite(spectra.grey, "spectra grey finite");
  checkFinite(spectra.spectrum, "spectrum finite");
  checkFinite(spectra.log_polar_spectrum, "log-polar spectrum finite");
  checkFinite(spectra.texture, "spectra texture finite");
}

void analyse(const cv::Mat& image) {
  try {
    checkPrepared(oefmt::prepareImage(image, kSize), image);
    checkSpectra(registrar().analyse(image));
  } catch (const oefmt::InputError&) {
    // Documented: unsupported pixel types (e.g. a decoded 16-bit colour PNG).
  }
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  // One thread: reproducible runs. (scripts/hardening.sh also sets OPENCV_IO_MAX_IMAGE_PIXELS,
  // read by OpenCV at load time, so that a header claiming gigapixels is refused instead of
  // exhausting the fuzzer's memory limit.)
  cv::setNumThreads(0);
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (looksCompressed(data, size)) {
    cv::Mat decoded;
    try {
      decoded = oefmt::decodeImage(data, size);
    } catch (const oefmt::InputError&) {
      return 0;  // documented: not a readable image (corrupt, truncated, over the pixel limit)
    }
    const cv::Mat bytes(1, static_cast<int>(size), CV_8UC1, const_cast<uint8_t*>(data));
    cv::Mat reference;
    try {
      reference = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
    } catch (const cv::Exception&) {
    }
    // Where both decode the bytes, the pictures must be identical.
    if (!reference.empty()) {
      oefmt_fuzz::check(reference.type() == decoded.type() && reference.size() == decoded.size(),
                        "decodeImage: type or size differs from cv::imdecode");
      oefmt_fuzz::check(cv::norm(reference, decoded, cv::NORM_INF) == 0.0,
                        "decodeImage: pixels differ from cv::imdecode");
    }
    if (const std::optional<cv::Mat> fast = oefmt::detail::decodeColourPngFast(data, size)) {
      cv::Mat libspng;
      try {
        libspng = oefmt::detail::decodePngLibspng(data, size);
      } catch (const oefmt::InputError&) {
        // An ancillary chunk libspng is stricter about than libpng (and the fast path): allowed.
      }
      if (!libspng.empty()) {
        oefmt_fuzz::check(libspng.type() == fast->type() && libspng.size() == fast->size() &&
                              cv::norm(libspng, *fast, cv::NORM_INF) == 0.0,
                          "PNG fast path: picture differs from libspng's");
      }
    }
    analyse(decoded);
    return 0;
  }
  FuzzedDataProvider input(data, size);
  analyse(rawImage(input));
  return 0;
}
