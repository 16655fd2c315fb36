// SPDX-License-Identifier: GPL-3.0-or-later
// Ray-casting renderer of the down-looking camera over a Scene: per-pixel rays (distortion
// included) computed once, supersampled, rows in parallel.
#pragma once

#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/io/dataset.h"
#include "oefmt/sim/camera_model.h"
#include "oefmt/sim/scene.h"

namespace oefmt {
namespace sim {

/// A rendered frame.
struct RenderedFrame {
  cv::Mat1f image;  ///< intensities in [0, 1]
  /// Surface seen by each pixel: 0 ground, k a top of raised level k, kWallLayers + k a side wall
  /// of a level-k top (scenes with walls only); kMixedLayers where the pixel's samples saw
  /// different ones (an edge of a top or wall).
  cv::Mat1b layers;
  static constexpr unsigned char kWallLayers = 128;
  static constexpr unsigned char kMixedLayers = 255;
};

class Renderer {
 public:
  /// supersample: s x s rays per pixel (anti-aliasing), >= 1. Throws InputError for invalid
  /// intrinsics or supersampling.
  Renderer(std::shared_ptr<const Scene> scene, const CameraParameters& camera, int supersample = 2);

  /// Renders the view from `pose` (the camera must be above every layer).
  RenderedFrame render(const FlightPose& pose) const;

  const CameraParameters& camera() const { return camera_; }
  int supersample() const { return supersample_; }

 private:
  std::shared_ptr<const Scene> scene_;
  CameraParameters camera_;
  int supersample_;
  /// Per sample, the ray in the optical frame as (x, y) with z = 1 (undistorted, normalised);
  /// samples of a pixel are consecutive, pixels row-major.
  std::vector<cv::Vec2f> rays_;
};

}  // namespace sim
}  // namespace oefmt
