// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/io/undistortion.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>
#include <vector>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"

namespace oefmt {
namespace {

// The undistorted view may zoom in at most this much (its focal length over the calibration's):
// beyond it less than half of the field of view is left, which no real lens with a fitting
// calibration needs; it is an absurd calibration, or one of another lens.
constexpr double kMaxZoom = 2.0;
// Output border pixels whose rays from the centre are checked for folding (per edge), and the
// samples along each ray. The full map is checked afterwards; these steer the search.
constexpr int kRaysPerEdge = 64;
constexpr int kRaySteps = 32;

std::string sizeText(cv::Size size) {
  return std::to_string(size.width) + "x" + std::to_string(size.height);
}

std::string format(const char* pattern, double a, double b, double c, double d) {
  char text[160];
  std::snprintf(text, sizeof(text), pattern, a, b, c, d);
  return text;
}

void requireFinite(const Distortion& d) {
  const std::pair<const char*, double> named[] = {{"k1", d.k1}, {"k2", d.k2}, {"p1", d.p1}, {"p2", d.p2},
                                                  {"k3", d.k3}, {"k4", d.k4}, {"k5", d.k5}, {"k6", d.k6}};
  for (const auto& [name, value] : named) {
    if (!std::isfinite(value)) throw InputError(std::string("lens distortion coefficient ") + name + " is not finite");
  }
}

// The calibration in pixels of images of image_size; width/height 0 means "the images' own".
Intrinsics mapToImage(Intrinsics calibration, cv::Size image_size) {
  if (!(std::isfinite(calibration.fx) && std::isfinite(calibration.fy) && std::isfinite(calibration.cx) &&
        std::isfinite(calibration.cy))) {
    throw InputError("camera intrinsics are not finite");
  }
  if (calibration.width <= 0 || calibration.height <= 0) {
    calibration.width = image_size.width;
    calibration.height = image_size.height;
  }
  const Intrinsics mapped = intrinsicsForImageSize(calibration, image_size);
  if (!(std::isfinite(mapped.fx) && std::isfinite(mapped.fy) && std::isfinite(mapped.cx) && std::isfinite(mapped.cy))) {
    throw InputError("camera intrinsics are out of range for the " + sizeText(image_size) + " images");
  }
  return mapped;
}

cv::Matx33d cameraMatrix(const Intrinsics& k) { return {k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0}; }

// Where the rays of output pixels land in the input image (pixels), for an output camera of
// focal length f with the principal point at `centre`.
std::vector<cv::Point2d> project(const std::vector<cv::Point2d>& output_pixels, double f, cv::Point2d centre,
                                 const CameraParameters& input) {
  std::vector<cv::Point3d> rays;
  rays.reserve(output_pixels.size());
  for (const cv::Point2d& p : output_pixels) rays.emplace_back((p.x - centre.x) / f, (p.y - centre.y) / f, 1.0);
  std::vector<cv::Point2d> pixels;
  cv::projectPoints(rays, cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cameraMatrix(input.intrinsics),
                    input.distortion.coefficients(), pixels);
  return pixels;
}

// Output pixels on the border (every one: where the view is limited) and rays from the centre
// to some of them (sampled: where a fold would show).
struct Probe {
  std::vector<cv::Point2d> border;
  std::vector<cv::Point2d> ray_points;  // kRaySteps per ray, from the centre outwards
  std::vector<cv::Point2d> ray_directions;
};

Probe makeProbe(cv::Size size, cv::Point2d centre) {
  Probe probe;
  const double right = size.width - 1, bottom = size.height - 1;
  for (int u = 0; u < size.width; ++u) {
    probe.border.emplace_back(u, 0.0);
    probe.border.emplace_back(u, bottom);
  }
  for (int v = 1; v + 1 < size.height; ++v) {
    probe.border.emplace_back(0.0, v);
    probe.border.emplace_back(right, v);
  }
  std::vector<cv::Point2d> ends;
  for (int i = 0; i <= kRaysPerEdge; ++i) {
    const double t = static_cast<double>(i) / kRaysPerEdge;
    ends.emplace_back(t * right, 0.0);
    ends.emplace_back(t * right, bottom);
    ends.emplace_back(0.0, t * bottom);
    ends.emplace_back(right, t * bottom);
  }
  for (const cv::Point2d& end : ends) {
    probe.ray_directions.push_back(end - centre);
    for (int s = 1; s <= kRaySteps; ++s) probe.ray_points.push_back(centre + (end - centre) * (double(s) / kRaySteps));
  }
  return probe;
}

bool inside(const cv::Point2d& p, cv::Size size) {
  // Pixel centres span [0, size - 1]; the bicubic kernel's reach beyond the last one reads the
  // edge pixels replicated (BORDER_REPLICATE), still the image's own values.
  return p.x >= 0.0 && p.y >= 0.0 && p.x <= size.width - 1 && p.y <= size.height - 1;
}

// True when, with focal length f, every probed output pixel lands inside the input and the
// input position moves outwards along every probed ray (no fold).
bool viewFits(double f, const Probe& probe, cv::Point2d centre, const CameraParameters& input, cv::Size size) {
  for (const cv::Point2d& p : project(probe.border, f, centre, input)) {
    if (!inside(p, size)) return false;
  }
  const std::vector<cv::Point2d> along = project(probe.ray_points, f, centre, input);
  const cv::Point2d principal(input.intrinsics.cx, input.intrinsics.cy);
  for (std::size_t r = 0; r < probe.ray_directions.size(); ++r) {
    cv::Point2d previous = principal;
    for (int s = 0; s < kRaySteps; ++s) {
      const cv::Point2d& p = along[r * kRaySteps + s];
      if (!inside(p, size) || !((p - previous).dot(probe.ray_directions[r]) > 0.0)) return false;
      previous = p;
    }
  }
  return true;
}

// Counts places where the map folds (its Jacobian determinant is not positive) and map positions
// outside the input (beyond rounding).
void checkMap(const cv::Mat1f& map_x, const cv::Mat1f& map_y, cv::Size size, long& outside, long& folded) {
  outside = folded = 0;
  for (int v = 0; v + 1 < map_x.rows; ++v) {
    for (int u = 0; u + 1 < map_x.cols; ++u) {
      const double xu = map_x(v, u + 1) - map_x(v, u), yu = map_y(v, u + 1) - map_y(v, u);
      const double xv = map_x(v + 1, u) - map_x(v, u), yv = map_y(v + 1, u) - map_y(v, u);
      if (!(xu * yv - xv * yu > 0.0)) ++folded;
    }
  }
  constexpr float kRounding = 1e-2f;  // [px] float maps versus projectPoints' doubles
  const float right = static_cast<float>(size.width - 1), bottom = static_cast<float>(size.height - 1);
  for (int v = 0; v < map_x.rows; ++v) {
    for (int u = 0; u < map_x.cols; ++u) {
      const float x = map_x(v, u), y = map_y(v, u);
      if (!(x >= -kRounding && y >= -kRounding && x <= right + kRounding && y <= bottom + kRounding)) ++outside;
    }
  }
}

}  // namespace

std::string describeSizeMapping(const Intrinsics& calibration, cv::Size image_size, const std::string& source) {
  if (calibration.width <= 0 || calibration.height <= 0 ||
      (calibration.width == image_size.width && calibration.height == image_size.height)) {
    return "";
  }
  const Intrinsics k = intrinsicsForImageSize(calibration, image_size);
  const cv::Size2d exact_crop = centredCropForImageSize(calibration, image_size);
  const cv::Size crop(static_cast<int>(std::lround(exact_crop.width)),
                      static_cast<int>(std::lround(exact_crop.height)));
  const bool cropped = crop.width != calibration.width || crop.height != calibration.height;
  return source + " describes a " + sizeText({calibration.width, calibration.height}) + " camera; the " +
         sizeText(image_size) + " images are taken as its " +
         (cropped ? "centred " + sizeText(crop) + " crop resized" : "whole image resized") + ": " +
         format("fx %.1f px, fy %.1f px, cx %.1f, cy %.1f", k.fx, k.fy, k.cx, k.cy);
}

bool sameCamera(const CameraParameters& a, const CameraParameters& b) {
  const Intrinsics &i = a.intrinsics, &j = b.intrinsics;
  const Distortion &d = a.distortion, &e = b.distortion;
  return i.fx == j.fx && i.fy == j.fy && i.cx == j.cx && i.cy == j.cy && i.width == j.width && i.height == j.height &&
         d.k1 == e.k1 && d.k2 == e.k2 && d.p1 == e.p1 && d.p2 == e.p2 && d.k3 == e.k3 && d.k4 == e.k4 &&
         d.k5 == e.k5 && d.k6 == e.k6;
}

CameraParameters pinholeCamera(double fx, cv::Size image_size) {
  CameraParameters camera;
  camera.intrinsics.fx = camera.intrinsics.fy = fx;
  camera.intrinsics.cx = (image_size.width - 1) / 2.0;
  camera.intrinsics.cy = (image_size.height - 1) / 2.0;
  camera.intrinsics.width = image_size.width;
  camera.intrinsics.height = image_size.height;
  return camera;
}

Undistorter::Undistorter(const CameraParameters& camera, cv::Size image_size, int working_size,
                         const std::string& source)
    : image_size_(image_size), source_(source), calibration_(camera) {
  try {
    setUp(working_size);
  } catch (const InputError& e) {
    throw InputError(source_ + ": " + e.what());
  }
}

void Undistorter::setUp(int working_size) {
  if (image_size_.width <= 0 || image_size_.height <= 0) throw InputError("the image size must be > 0");
  if (working_size <= 0) throw InputError("the working size must be > 0");
  requireFinite(calibration_.distortion);
  input_.intrinsics = mapToImage(calibration_.intrinsics, image_size_);
  input_.distortion = calibration_.distortion;
  output_ = input_.intrinsics;
  // What the core makes of a frame: its centred square, resized to the working size.
  const int side = std::min(image_size_.width, image_size_.height);
  const double scale = static_cast<double>(working_size) / side;
  working_fx_ = output_.fx * scale;
  if (!input_.distortion.any()) return;

  const Intrinsics& k = input_.intrinsics;
  const std::string lens = "lens distortion (" + input_.distortion.text() + ")";
  if (!inside({k.cx, k.cy}, image_size_)) {
    throw InputError(lens + ": the principal point " + format("(%.1f, %.1f)", k.cx, k.cy, 0.0, 0.0) +
                     " lies outside the " + sizeText(image_size_) + " image");
  }
  // The working frame: square pixels and the principal point at the centre, what the
  // registration assumes.
  const cv::Size working(working_size, working_size);
  const cv::Point2d centre((working_size - 1) / 2.0, (working_size - 1) / 2.0);
  lens_fx_ = std::sqrt(k.fx * k.fy) * scale;
  const Probe probe = makeProbe(working, centre);
  double f = lens_fx_;
  if (!viewFits(f, probe, centre, input_, image_size_)) {
    double narrow = kMaxZoom * lens_fx_, wide = lens_fx_;
    if (!viewFits(narrow, probe, centre, input_, image_size_)) {
      throw InputError(lens + " cannot be undone over the " + sizeText(image_size_) +
                       " image: even the central half of the view maps outside it or folds over "
                       "(absurd coefficients, or another lens's calibration)");
    }
    // The widest view that fits, by bisection on log f (fitting views nest: a narrower one is
    // a part of a wider one that fits).
    for (int iteration = 0; iteration < 40; ++iteration) {
      const double middle = std::sqrt(narrow * wide);
      (viewFits(middle, probe, centre, input_, image_size_) ? narrow : wide) = middle;
    }
    f = narrow;
  }
  output_ = Intrinsics{f, f, centre.x, centre.y, working_size, working_size};
  working_fx_ = f;

  cv::Mat map_x, map_y;
  cv::initUndistortRectifyMap(cameraMatrix(k), input_.distortion.coefficients(), cv::noArray(),
                              cameraMatrix(output_), working, CV_32FC1, map_x, map_y);
  cv::Mat1f mx = map_x, my = map_y;
  long outside = 0, folded = 0;
  checkMap(mx, my, image_size_, outside, folded);
  if (outside > 0 || folded > 0) {
    throw InputError(lens + " cannot be undone over the " + sizeText(image_size_) + " image: " +
                     std::to_string(outside) + " pixels would come from outside it and " +
                     std::to_string(folded) + " from where the lens model folds over");
  }
  // Only the part of the frame the working frame samples is converted (and shrunk): its
  // bounding box, with the bicubic kernel's reach.
  double x_min = 0.0, x_max = 0.0, y_min = 0.0, y_max = 0.0;
  cv::minMaxLoc(mx, &x_min, &x_max);
  cv::minMaxLoc(my, &y_min, &y_max);
  const int x0 = std::max(0, static_cast<int>(std::floor(x_min)) - 2);
  const int y0 = std::max(0, static_cast<int>(std::floor(y_min)) - 2);
  const int x1 = std::min(image_size_.width, static_cast<int>(std::ceil(x_max)) + 3);
  const int y1 = std::min(image_size_.height, static_cast<int>(std::ceil(y_max)) + 3);
  roi_ = cv::Rect(x0, y0, x1 - x0, y1 - y0);
  // A frame larger than the working scale is shrunk first by area interpolation (as
  // prepareImage shrinks an undistorted one), so the remap neither aliases nor costs more than
  // the working size.
  double sx = 1.0, sy = 1.0;
  cv::Size source = roi_.size();
  if (scale < 1.0) {
    reduced_ = cv::Size(std::max(1, static_cast<int>(std::lround(roi_.width * scale))),
                        std::max(1, static_cast<int>(std::lround(roi_.height * scale))));
    sx = static_cast<double>(reduced_.width) / roi_.width;
    sy = static_cast<double>(reduced_.height) / roi_.height;
    source = reduced_;
  }
  const float right = static_cast<float>(source.width - 1), bottom = static_cast<float>(source.height - 1);
  for (int v = 0; v < mx.rows; ++v) {
    for (int u = 0; u < mx.cols; ++u) {
      // Pixel centres at integer coordinates: a resize by s maps x to (x + 0.5) s - 0.5.
      mx(v, u) = std::clamp(static_cast<float>((mx(v, u) - x0 + 0.5) * sx - 0.5), 0.0f, right);
      my(v, u) = std::clamp(static_cast<float>((my(v, u) - y0 + 0.5) * sy - 0.5), 0.0f, bottom);
    }
  }
  cv::convertMaps(mx, my, map_xy_, map_fraction_, CV_16SC2);
  // The same sampling as a camera: the lens's intrinsics in the pixels of the (shrunk) part,
  // offset by the margin sourceFrame() adds.
  source_camera_.distortion = input_.distortion;
  source_camera_.intrinsics = Intrinsics{k.fx * sx,
                                         k.fy * sy,
                                         (k.cx - x0 + 0.5) * sx - 0.5 + kSourceMargin,
                                         (k.cy - y0 + 0.5) * sy - 0.5 + kSourceMargin,
                                         source.width + 2 * kSourceMargin,
                                         source.height + 2 * kSourceMargin};

  // The horizontal field of view kept, for describe(): the lens's over the square's middle row.
  const double left = (image_size_.width - side) / 2.0;
  std::vector<cv::Point2d> ends{{left, k.cy}, {left + side - 1.0, k.cy}}, normalised;
  cv::undistortPoints(ends, normalised, cameraMatrix(k), input_.distortion.coefficients());
  const double lens_width = (normalised[1].x - normalised[0].x) * side / (side - 1.0);
  kept_width_ = lens_width > 0.0 ? working_size / output_.fx / lens_width : 1.0;
}

cv::Mat1f Undistorter::sampledPart(const cv::Mat& image, ChannelOrder order) const {
  // The working frame would hide a frame too small to register: refused as prepareImage does.
  requireRegistrableSize(image);
  if (image.size() != image_size_) {
    throw InputError("the frame is " + sizeText(image.size()) + " but the undistortion was set up for " +
                     sizeText(image_size_) + " frames");
  }
  cv::Mat1f grey = toGreyFloat(image(roi_), order);
  if (!reduced_.empty()) {
    cv::Mat1f shrunk;
    cv::resize(grey, shrunk, reduced_, 0.0, 0.0, cv::INTER_AREA);
    grey = shrunk;
  }
  return grey;
}

cv::Mat Undistorter::apply(const cv::Mat& image, ChannelOrder order) const {
  if (!remaps()) return image;
  cv::Mat1f undistorted;
  cv::remap(sampledPart(image, order), undistorted, map_xy_, map_fraction_, cv::INTER_CUBIC, cv::BORDER_REPLICATE);
  return undistorted;
}

cv::Mat1f Undistorter::sourceFrame(const cv::Mat& image, ChannelOrder order) const {
  if (!remaps()) throw InputError("no lens distortion to undo: the frames are used as they are");
  cv::Mat1f padded;
  cv::copyMakeBorder(sampledPart(image, order), padded, kSourceMargin, kSourceMargin, kSourceMargin,
                     kSourceMargin, cv::BORDER_REPLICATE);
  return padded;
}

std::vector<std::string> Undistorter::notes() const {
  std::vector<std::string> lines;
  const std::string mapping = describeSizeMapping(calibration_.intrinsics, image_size_, source_);
  if (!mapping.empty()) lines.push_back(mapping);
  if (remaps()) lines.push_back(describe());
  return lines;
}

std::string Undistorter::describe() const {
  if (!remaps()) return "no lens distortion: frames used as they are";
  const int side = std::min(image_size_.width, image_size_.height);
  const std::string from = image_size_.width == image_size_.height
                               ? ""
                               : " from the " + sizeText(image_size_) + " frames' centred " +
                                     sizeText({side, side}) + " square";
  return "undistorting (" + source_ + ": " + input_.distortion.text() + "): " +
         sizeText({output_.width, output_.height}) + " working frames" + from + ", " +
         format("fx = fy %.1f px (the lens's %.1f), principal point at the centre, %.0f %% of the "
                "lens's horizontal field of view",
                output_.fx, lens_fx_, 100.0 * kept_width_, 0.0);
}

}  // namespace oefmt
