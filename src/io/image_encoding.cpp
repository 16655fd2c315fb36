// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/io/image_encoding.h"

#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <opencv2/imgcodecs.hpp>

#include "oefmt/error.h"

namespace oefmt {

std::vector<std::uint8_t> encodeImage(const std::string& extension, const cv::Mat& image) {
  std::vector<std::uint8_t> bytes;
  std::string error = "OpenCV cannot encode it";
  try {
    if (cv::imencode("." + extension, image, bytes)) return bytes;
  } catch (const cv::Exception& e) {
    error = e.err;
  }
  throw InputError("cannot encode an image of type " + cv::typeToString(image.type()) + " as '" + extension +
                   "': " + error);
}

void writeImageFile(const std::string& path, const cv::Mat& image) {
  std::string extension = std::filesystem::path(path).extension().string();
  if (!extension.empty()) extension.erase(0, 1);  // the dot
  const std::vector<std::uint8_t> bytes = encodeImage(extension, image);
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  file.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
  file.close();
  if (!file) throw std::runtime_error("cannot write image file '" + path + "'");
}

}  // namespace oefmt
