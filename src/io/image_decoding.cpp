// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/io/image_decoding.h"

#include <climits>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <optional>
#include <utility>
#include <vector>

#include <opencv2/imgcodecs.hpp>

#include "oefmt/error.h"
#include "png_decoders.h"

namespace oefmt {
namespace {

constexpr std::uint8_t kPngSignature[8] = {137, 80, 78, 71, 13, 10, 26, 10};

cv::Mat decodeOther(const std::uint8_t* data, std::size_t size) {
  if (size > static_cast<std::size_t>(INT_MAX)) throw InputError("image data of more than 2 GB");
  cv::Mat image;
  try {
    // A view, not a copy: cv::imdecode only reads it.
    const cv::Mat buffer(1, static_cast<int>(size), CV_8U, const_cast<std::uint8_t*>(data));
    image = cv::imdecode(buffer, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception& e) {  // some damaged files throw instead of giving nothing
    throw InputError("corrupt image (OpenCV: " + e.err + ")");
  }
  if (image.empty()) throw InputError("not an image OpenCV can read (unknown format, corrupt or truncated)");
  return image;
}

}  // namespace

cv::Mat decodeImage(const std::uint8_t* data, std::size_t size) {
  if (data == nullptr || size == 0) throw InputError("no image data");
  if (size >= sizeof(kPngSignature) && std::memcmp(data, kPngSignature, sizeof(kPngSignature)) == 0) {
    if (std::optional<cv::Mat> image = detail::decodeColourPngFast(data, size)) return std::move(*image);
    return detail::decodePngLibspng(data, size);
  }
  return decodeOther(data, size);
}

cv::Mat readImageFile(const std::string& path) {
  const std::string what = "cannot read image '" + path + "': ";
  std::vector<std::uint8_t> bytes;
  {
    std::ifstream file(path, std::ios::binary | std::ios::ate);
    if (!file) throw InputError(what + (std::filesystem::exists(path) ? "cannot open it" : "no such file"));
    const std::streamoff length = file.tellg();
    if (length < 0) throw InputError(what + "cannot read it");
    if (length == 0) throw InputError(what + "empty file");
    bytes.resize(static_cast<std::size_t>(length));
    file.seekg(0);
    if (!file.read(reinterpret_cast<char*>(bytes.data()), length)) throw InputError(what + "cannot read it");
  }
  try {
    return decodeImage(bytes.data(), bytes.size());
  } catch (const InputError& e) {
    throw InputError(what + e.what());
  }
}

}  // namespace oefmt
