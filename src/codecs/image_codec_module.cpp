// SPDX-License-Identifier: GPL-3.0-or-later
// liboefmt_image_codecs.so: OpenCV's imgcodecs behind the table the core loads on first use
// (see src/io/image_codec_module.h for why it is a plugin).
#include <climits>

#include <opencv2/imgcodecs.hpp>

#include "image_codec_module.h"

namespace {

cv::Mat decode(const std::uint8_t* data, std::size_t size) {
  if (data == nullptr || size == 0 || size > static_cast<std::size_t>(INT_MAX)) return cv::Mat();
  try {
    // A view, not a copy: cv::imdecode only reads it.
    const cv::Mat buffer(1, static_cast<int>(size), CV_8U, const_cast<std::uint8_t*>(data));
    return cv::imdecode(buffer, cv::IMREAD_UNCHANGED);
  } catch (const cv::Exception&) {
    return cv::Mat();  // OpenCV throws on some damaged files instead of returning empty
  }
}

bool encode(const std::string& extension, const cv::Mat& image, std::vector<std::uint8_t>& bytes,
            std::string& error) {
  try {
    if (cv::imencode("." + extension, image, bytes)) return true;
    error = "OpenCV cannot encode it";
  } catch (const cv::Exception& e) {
    error = e.err;
  }
  return false;
}

const oefmt::detail::ImageCodecModule kModule{oefmt::detail::kImageCodecModuleVersion, &decode,
                                              &encode};

}  // namespace

extern "C" __attribute__((visibility("default"))) const oefmt::detail::ImageCodecModule*
oefmt_image_codec_module() {
  return &kModule;
}
