// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/io/nadir_view.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"

namespace oefmt {
namespace {

cv::Matx33d cameraMatrix(const Intrinsics& k) { return {k.fx, 0.0, k.cx, 0.0, k.fy, k.cy, 0.0, 0.0, 1.0}; }

}  // namespace

NadirView::NadirView(const CameraParameters& camera, cv::Size image_size, double working_fx, int working_size)
    : source_camera_(camera), image_size_(image_size), working_size_(working_size) {
  const Intrinsics& k = camera.intrinsics;
  if (!k.valid() || image_size.width <= 0 || image_size.height <= 0 || !(working_fx > 0.0) || working_size < 16) {
    throw InputError("nadir view: invalid intrinsics, frame size or working size");
  }
  // A frame much finer than the working image is shrunk first (area interpolation), so the
  // resampling neither aliases nor costs more than the working size.
  const double scale = working_fx / k.fx;
  if (scale < 0.75) {
    shrink_ = scale;
    Intrinsics& s = source_camera_.intrinsics;
    s.fx *= scale;
    s.fy *= scale;
    s.cx = (s.cx + 0.5) * scale - 0.5;
    s.cy = (s.cy + 0.5) * scale - 0.5;
  }
  fade_px_ = std::max(4.0, working_size / 16.0);
  const double centre = (working_size - 1) / 2.0;
  virtual_camera_ = cv::Matx33d(working_fx, 0.0, centre, 0.0, working_fx, centre, 0.0, 0.0, 1.0);
}

cv::Mat1f NadirView::apply(const cv::Mat& image, const Eigen::Matrix3d& nadir_from_optical, ChannelOrder order) const {
  return render(image, nadir_from_optical, order, nullptr);
}

PreparedImage NadirView::prepare(const cv::Mat& image, const Eigen::Matrix3d& nadir_from_optical,
                                 ChannelOrder order) const {
  cv::Mat1b seen;
  PreparedImage prepared = prepareImage(render(image, nadir_from_optical, order, &seen), working_size_);
  prepared.seen = seen;
  return prepared;
}

cv::Mat1f NadirView::render(const cv::Mat& image, const Eigen::Matrix3d& nadir_from_optical, ChannelOrder order,
                            cv::Mat1b* seen_out) const {
  if (image.size() != image_size_) {
    throw InputError("the frame is " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                     " but the nadir view was set up for " + std::to_string(image_size_.width) + "x" +
                     std::to_string(image_size_.height) + " frames");
  }
  cv::Mat1f grey = toGreyFloat(image, order);
  if (shrink_ < 1.0) {
    cv::Mat1f shrunk;
    cv::resize(grey, shrunk, cv::Size(), shrink_, shrink_, cv::INTER_AREA);
    grey = shrunk;
  }
  cv::Matx33d rotation;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) rotation(r, c) = nadir_from_optical(r, c);
  }
  // For each virtual pixel: its ray turned back into the real camera, distorted and projected.
  cv::Mat map_x, map_y;
  cv::initUndistortRectifyMap(cameraMatrix(source_camera_.intrinsics), source_camera_.distortion.coefficients(),
                              rotation, virtual_camera_, cv::Size(working_size_, working_size_), CV_32FC1, map_x,
                              map_y);
  // Seen is where a virtual pixel's ray lands on the frame (pixel centres at integer
  // coordinates, the frame's edge half a pixel beyond them) and the frame had a value there (a
  // float frame's NaN or inf is no sight either). Sampling replicates the border, so the bicubic
  // kernel's reach beyond the last pixel leaves the frame's edge rows seen: a level frame comes
  // out as it went in.
  cv::Mat1f view;
  cv::remap(grey, view, map_x, map_y, cv::INTER_CUBIC, cv::BORDER_REPLICATE);
  cv::Mat1b seen_x, seen_y, seen, finite;
  cv::inRange(map_x, -0.5, grey.cols - 0.5, seen_x);
  cv::inRange(map_y, -0.5, grey.rows - 0.5, seen_y);
  cv::inRange(view, -std::numeric_limits<float>::max(), std::numeric_limits<float>::max(), finite);
  cv::bitwise_and(seen_x, seen_y, seen);
  cv::bitwise_and(seen, finite, seen);
  // What the camera did not see fades out: within a ramp of the unseen part the texture blends
  // into the seen part's mean, which fills the rest. A hard edge there would move with the tilt
  // from frame to frame and pull the correlation as a texture of its own would. The ramp is no
  // wider than the unseen part is deep, so that it grows from nothing as the camera tilts away
  // from level: a fixed ramp would fade a whole band the moment a single pixel goes unseen, and
  // views of nearly the same attitude would differ by that band.
  const int seen_pixels = cv::countNonZero(seen);
  if (seen_pixels == 0) throw InputError("the camera saw none of the level view (tilted too far)");
  if (seen_out != nullptr) seen_out->release();
  if (seen_pixels == static_cast<int>(view.total())) return view;
  const double mean = cv::mean(view, seen)[0];
  cv::Mat1b unseen;
  cv::bitwise_not(seen, unseen);
  cv::Mat1f depth, distance;
  cv::distanceTransform(unseen, depth, cv::DIST_L2, cv::DIST_MASK_3);
  double deepest = 0.0;
  cv::minMaxLoc(depth, nullptr, &deepest);
  cv::distanceTransform(seen, distance, cv::DIST_L2, cv::DIST_MASK_3);
  const float ramp = static_cast<float>(std::clamp(deepest, 1.0, fade_px_));
  // The camera's own pixels are those the fade leaves as they are.
  if (seen_out != nullptr) cv::compare(distance, ramp, *seen_out, cv::CMP_GE);
  for (int y = 0; y < view.rows; ++y) {
    float* v = view[y];
    const float* d = distance[y];
    for (int x = 0; x < view.cols; ++x) {
      const float w = std::min(1.0f, d[x] / ramp);
      v[x] = w > 0.0f ? static_cast<float>(mean + (v[x] - mean) * (w * w * (3.0f - 2.0f * w))) : static_cast<float>(mean);
    }
  }
  return view;
}

}  // namespace oefmt
