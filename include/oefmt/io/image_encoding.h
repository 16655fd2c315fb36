// SPDX-License-Identifier: GPL-3.0-or-later
// Image file encoding (simulated flights, bags of compressed images) through OpenCV's imgcodecs.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

namespace oefmt {

/// `image` encoded as `extension` ("png", "jpg", ...: what cv::imencode takes, without the dot).
/// Throws InputError when OpenCV cannot encode this image so.
std::vector<std::uint8_t> encodeImage(const std::string& extension, const cv::Mat& image);

/// Writes encodeImage(the extension of `path`, image) to `path`. Throws as encodeImage, and
/// std::runtime_error when the file cannot be written.
void writeImageFile(const std::string& path, const cv::Mat& image);

}  // namespace oefmt
