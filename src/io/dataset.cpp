// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/io/dataset.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <utility>

#include "oefmt/error.h"
#include "oefmt/io/image_decoding.h"
#include "yaml_document.h"

namespace oefmt {
namespace fs = std::filesystem;
namespace {

// readImageFile, or a DatasetError naming the file: missing, unreadable, corrupt or truncated,
// over the size limit, or of no format the decoders know.
cv::Mat readDatasetImage(const std::string& path) {
  try {
    return readImageFile(path);
  } catch (const InputError& e) {
    if (!fs::exists(path)) throw DatasetError("image '" + path + "' does not exist");
    throw DatasetError(e.what());  // names the file
  }
}

std::string trim(const std::string& text) {
  const auto first = text.find_first_not_of(" \t\r\n");
  if (first == std::string::npos) return "";
  const auto last = text.find_last_not_of(" \t\r\n");
  return text.substr(first, last - first + 1);
}

// Non-blank, non-comment lines of a text file, trimmed (CR LF and a missing final newline are fine).
std::vector<std::string> readLines(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw DatasetError("cannot open '" + path + "'");
  std::vector<std::string> lines;
  std::string line;
  while (std::getline(in, line)) {
    line = trim(line);
    if (!line.empty() && line[0] != '#') lines.push_back(line);
  }
  return lines;
}

std::string readWholeFile(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw DatasetError("cannot open camera parameters '" + path + "'");
  std::ostringstream text;
  text << in.rdbuf();
  return text.str();
}

// Camera.<key>'s node; an undefined node when the file has no such key.
YAML::Node cameraKey(const YAML::Node& root, const char* key) {
  const YAML::Node& map = root;  // const: operator[] must not add the key
  return map[std::string("Camera.") + key];
}

// Reads Camera.<key> as a number; `fallback` when absent (or null) and not required.
double readNumber(const YAML::Node& root, const std::string& path, const char* key, bool required,
                  double fallback) {
  const YAML::Node node = cameraKey(root, key);
  if (!node.IsDefined() || node.IsNull()) {
    if (required) throw DatasetError("'" + path + "' has no Camera." + key);
    return fallback;
  }
  const std::string where = yamlWhere("'" + path + "'", node);
  double value = 0.0;
  if (!node.IsScalar() || !yamlNumber(node.Scalar(), value)) {
    throw DatasetError(where + ": Camera." + key + " is not a number");
  }
  if (!std::isfinite(value)) throw DatasetError(where + ": Camera." + key + " is not finite");
  return value;
}

bool isImageFile(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  return ext == ".png" || ext == ".jpg" || ext == ".jpeg" || ext == ".tif" || ext == ".tiff" ||
         ext == ".bmp";
}

// "PinHole" as the authors (and ORB-SLAM) write it; case and quotes are not significant.
bool isPinhole(std::string type) {
  std::transform(type.begin(), type.end(), type.begin(), [](unsigned char c) { return std::tolower(c); });
  return type == "pinhole";
}

std::string sizeText(cv::Size size) {
  return std::to_string(size.width) + "x" + std::to_string(size.height);
}

}  // namespace

std::vector<double> Distortion::coefficients() const {
  std::vector<double> c{k1, k2, p1, p2, k3};
  if (rational()) c.insert(c.end(), {k4, k5, k6});
  return c;
}

std::string Distortion::text() const {
  std::ostringstream out;
  const std::pair<const char*, double> named[] = {{"k1", k1}, {"k2", k2}, {"p1", p1}, {"p2", p2},
                                                  {"k3", k3}, {"k4", k4}, {"k5", k5}, {"k6", k6}};
  for (const auto& [name, value] : named) {
    if (value != 0.0) out << (out.tellp() > 0 ? " " : "") << name << ' ' << value;
  }
  return out.tellp() > 0 ? out.str() : "none";
}

CameraParameters readCameraParameters(const std::string& path) {
  YAML::Node root;
  try {
    root = parseYamlMap(readWholeFile(path), "camera parameters '" + path + "'");
  } catch (const InputError& e) {
    throw DatasetError(e.what());
  }
  CameraParameters camera;
  Intrinsics& k = camera.intrinsics;
  k.fx = readNumber(root, path, "fx", true, 0.0);
  k.fy = readNumber(root, path, "fy", true, 0.0);
  k.cx = readNumber(root, path, "cx", true, 0.0);
  k.cy = readNumber(root, path, "cy", true, 0.0);
  k.width = static_cast<int>(std::lround(readNumber(root, path, "width", false, 0.0)));
  k.height = static_cast<int>(std::lround(readNumber(root, path, "height", false, 0.0)));
  if (!(k.fx > 0.0 && k.fy > 0.0)) throw DatasetError("'" + path + "': Camera.fx and fy must be > 0");
  if (k.width < 0 || k.height < 0) throw DatasetError("'" + path + "': negative Camera.width/height");
  const YAML::Node type = cameraKey(root, "type");
  if (type.IsDefined() && type.IsScalar() && !isPinhole(type.Scalar())) {
    throw DatasetError(yamlWhere("'" + path + "'", type) + ": Camera.type '" + type.Scalar() +
                       "' is not supported (PinHole: k1, k2, p1, p2, k3 and rational k4, k5, k6)");
  }
  Distortion& d = camera.distortion;
  d.k1 = readNumber(root, path, "k1", false, 0.0);
  d.k2 = readNumber(root, path, "k2", false, 0.0);
  d.p1 = readNumber(root, path, "p1", false, 0.0);
  d.p2 = readNumber(root, path, "p2", false, 0.0);
  d.k3 = readNumber(root, path, "k3", false, 0.0);
  d.k4 = readNumber(root, path, "k4", false, 0.0);
  d.k5 = readNumber(root, path, "k5", false, 0.0);
  d.k6 = readNumber(root, path, "k6", false, 0.0);
  return camera;
}

void writeCameraParameters(const std::string& path, const CameraParameters& camera) {
  const Intrinsics& k = camera.intrinsics;
  const Distortion& d = camera.distortion;
  std::ofstream out(path);
  if (!out) throw DatasetError("cannot write camera parameters '" + path + "'");
  out.precision(10);
  out << "%YAML:1.0\n\nCamera.type: \"PinHole\"\n\n"
      << "Camera.fx: " << k.fx << "\nCamera.fy: " << k.fy << "\nCamera.cx: " << k.cx
      << "\nCamera.cy: " << k.cy << "\n\nCamera.k1: " << d.k1 << "\nCamera.k2: " << d.k2
      << "\nCamera.p1: " << d.p1 << "\nCamera.p2: " << d.p2 << "\n";
  // The authors' file has no k3..k6: written only when they carry something.
  const std::pair<const char*, double> higher[] = {{"k3", d.k3}, {"k4", d.k4}, {"k5", d.k5}, {"k6", d.k6}};
  for (const auto& [name, value] : higher) {
    if (value != 0.0) out << "Camera." << name << ": " << value << "\n";
  }
  out << "\nCamera.width: " << k.width
      << "\nCamera.height: " << k.height << "\n";
  if (!out) throw DatasetError("cannot write camera parameters '" + path + "'");
}

cv::Size2d centredCropForImageSize(const Intrinsics& camera, cv::Size image_size) {
  const double aspect = static_cast<double>(image_size.width) / image_size.height;
  cv::Size2d crop(camera.width, camera.height);
  if (crop.width / crop.height > aspect) {
    crop.width = crop.height * aspect;
  } else {
    crop.height = crop.width / aspect;
  }
  return crop;
}

Intrinsics intrinsicsForImageSize(const Intrinsics& camera, cv::Size image_size) {
  if (!camera.valid()) throw InputError("camera intrinsics are invalid (fx, fy, width, height must be > 0)");
  if (image_size.width <= 0 || image_size.height <= 0) throw InputError("image size must be > 0");
  const cv::Size2d crop = centredCropForImageSize(camera, image_size);
  const double crop_w = crop.width, crop_h = crop.height;
  const double x0 = (camera.width - crop_w) / 2.0;
  const double y0 = (camera.height - crop_h) / 2.0;
  const double kx = image_size.width / crop_w;
  const double ky = image_size.height / crop_h;
  Intrinsics out;
  out.fx = camera.fx * kx;
  out.fy = camera.fy * ky;
  out.cx = (camera.cx - x0 + 0.5) * kx - 0.5;
  out.cy = (camera.cy - y0 + 0.5) * ky - 0.5;
  out.width = image_size.width;
  out.height = image_size.height;
  return out;
}

bool parseTimestamp(const std::string& raw, double& seconds) {
  const std::string text = trim(raw);
  if (text.empty()) return false;
  const bool all_digits = std::all_of(text.begin(), text.end(), [](unsigned char c) { return std::isdigit(c); });
  if (all_digits && text.size() == 14) {
    std::tm tm{};
    tm.tm_year = std::stoi(text.substr(0, 4)) - 1900;
    tm.tm_mon = std::stoi(text.substr(4, 2)) - 1;
    tm.tm_mday = std::stoi(text.substr(6, 2));
    tm.tm_hour = std::stoi(text.substr(8, 2));
    tm.tm_min = std::stoi(text.substr(10, 2));
    tm.tm_sec = std::stoi(text.substr(12, 2));
    if (tm.tm_mon < 0 || tm.tm_mon > 11 || tm.tm_mday < 1 || tm.tm_mday > 31 || tm.tm_hour > 23 ||
        tm.tm_min > 59 || tm.tm_sec > 60) {
      return false;
    }
    seconds = static_cast<double>(timegm(&tm));
    return true;
  }
  std::size_t used = 0;
  try {
    seconds = std::stod(text, &used);
  } catch (const std::exception&) {
    return false;
  }
  return used == text.size() && std::isfinite(seconds);
}

FolderDataset::FolderDataset(const std::string& directory) : directory_(directory) {
  if (!fs::is_directory(directory_)) throw DatasetError("dataset folder '" + directory_ + "' does not exist");
  readImageList();
  if (names_.empty()) throw DatasetError("dataset '" + directory_ + "' lists no image");

  image_size_ = readDatasetImage(paths_[0]).size();

  const std::string yaml = (fs::path(directory_) / "cam_param.yaml").string();
  if (!fs::exists(yaml)) throw DatasetError("dataset '" + directory_ + "' has no cam_param.yaml");
  camera_ = readCameraParameters(yaml);
  file_intrinsics_ = camera_.intrinsics;
  if (file_intrinsics_.width <= 0 || file_intrinsics_.height <= 0) {
    warnings_.push_back("cam_param.yaml gives no Camera.width/height: taken as the image size " +
                        sizeText(image_size_));
    file_intrinsics_.width = image_size_.width;
    file_intrinsics_.height = image_size_.height;
  }
  camera_.intrinsics = intrinsicsForImageSize(file_intrinsics_, image_size_);
  readTimestamps();
}

void FolderDataset::readImageList() {
  const fs::path root(directory_);
  const fs::path list = root / "imageList.txt";
  const fs::path images = root / "Images";
  if (fs::exists(list)) {
    names_ = readLines(list.string());
    for (const std::string& name : names_) {
      const fs::path in_images = images / name;
      paths_.push_back((fs::exists(in_images) || !fs::exists(root / name) ? in_images : root / name).string());
    }
    return;
  }
  if (!fs::is_directory(images)) {
    throw DatasetError("dataset '" + directory_ + "' has neither imageList.txt nor an Images folder");
  }
  warnings_.push_back("no imageList.txt: using every image in Images/ in name order");
  for (const auto& entry : fs::directory_iterator(images)) {
    if (entry.is_regular_file() && isImageFile(entry.path())) names_.push_back(entry.path().filename().string());
  }
  std::sort(names_.begin(), names_.end());
  for (const std::string& name : names_) paths_.push_back((images / name).string());
}

void FolderDataset::readTimestamps() {
  const fs::path file = fs::path(directory_) / "timestamps.txt";
  if (!fs::exists(file)) return;
  const std::vector<std::string> lines = readLines(file.string());
  const std::string ignored = "timestamps.txt ignored (frame k gets timestamp k): ";
  if (lines.size() != names_.size()) {
    warnings_.push_back(ignored + "it has " + std::to_string(lines.size()) + " stamps for " +
                        std::to_string(names_.size()) + " images");
    return;
  }
  std::vector<double> stamps(lines.size());
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (!parseTimestamp(lines[i], stamps[i])) {
      warnings_.push_back(ignored + "line " + std::to_string(i + 1) + " '" + lines[i] + "' is not a time");
      return;
    }
    if (i > 0 && !(stamps[i] > stamps[i - 1])) {
      warnings_.push_back(ignored + "stamps do not increase at line " + std::to_string(i + 1));
      return;
    }
  }
  timestamps_ = std::move(stamps);
  has_timestamps_ = true;
}

void FolderDataset::checkIndex(std::size_t index) const {
  if (index >= names_.size()) {
    throw InputError("frame " + std::to_string(index) + " is out of range (dataset has " +
                     std::to_string(names_.size()) + " images)");
  }
}

const std::string& FolderDataset::imageName(std::size_t index) const {
  checkIndex(index);
  return names_[index];
}

const std::string& FolderDataset::imagePath(std::size_t index) const {
  checkIndex(index);
  return paths_[index];
}

double FolderDataset::timestamp(std::size_t index) const {
  checkIndex(index);
  return has_timestamps_ ? timestamps_[index] : static_cast<double>(index);
}

void FolderDataset::adviseReading(std::size_t index) const {
  if (index >= paths_.size()) return;
  const int fd = ::open(paths_[index].c_str(), O_RDONLY | O_CLOEXEC);
  if (fd < 0) return;
  (void)::posix_fadvise(fd, 0, 0, POSIX_FADV_WILLNEED);
  ::close(fd);
}

cv::Mat FolderDataset::loadImage(std::size_t index) const {
  const std::string& path = imagePath(index);
  cv::Mat image = readDatasetImage(path);
  if (image.size() != image_size_) {
    throw DatasetError("image '" + path + "' is " + sizeText(image.size()) + " but the dataset's images are " +
                       sizeText(image_size_));
  }
  return image;
}

}  // namespace oefmt
