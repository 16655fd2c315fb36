// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/sim/renderer.h"

#include <cmath>
#include <string>

#include "oefmt/error.h"

namespace oefmt {
namespace sim {

Renderer::Renderer(std::shared_ptr<const Scene> scene, const CameraParameters& camera, int supersample)
    : scene_(std::move(scene)), camera_(camera), supersample_(supersample) {
  if (!scene_) throw InputError("renderer: no scene");
  const Intrinsics& k = camera_.intrinsics;
  if (!k.valid()) throw InputError("renderer: invalid intrinsics (fx, fy, width, height must be > 0)");
  if (supersample_ < 1 || supersample_ > 8) throw InputError("renderer: supersample must be in [1, 8]");
  // Sample (i, j) of pixel (u, v) sits at u + (i + 0.5) / s - 0.5: the samples tile the pixel.
  const int s = supersample_;
  rays_.reserve(static_cast<std::size_t>(k.width) * k.height * s * s);
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      for (int j = 0; j < s; ++j) {
        for (int i = 0; i < s; ++i) {
          const double px = u + (i + 0.5) / s - 0.5, py = v + (j + 0.5) / s - 0.5;
          const cv::Point2d n = undistortNormalised(camera_.distortion, {(px - k.cx) / k.fx, (py - k.cy) / k.fy});
          rays_.emplace_back(static_cast<float>(n.x), static_cast<float>(n.y));
        }
      }
    }
  }
}

RenderedFrame Renderer::render(const FlightPose& pose) const {
  const Scene& scene = *scene_;
  if (!(pose.position[2] > scene.config().highestTop())) {
    throw InputError("renderer: the camera (z = " + std::to_string(pose.position[2]) +
                     " m) must fly above the highest block top (" + std::to_string(scene.config().highestTop()) + " m)");
  }
  const Intrinsics& k = camera_.intrinsics;
  const int samples = supersample_ * supersample_;
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  const cv::Matx33d rotation = opticalToWorld(pose);
  const bool level = pose.level();
  const cv::Vec3d origin = pose.position;
  RenderedFrame frame;
  frame.image.create(k.height, k.width);
  frame.layers.create(k.height, k.width);
  cv::parallel_for_(cv::Range(0, k.height), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      float* out = frame.image[v];
      unsigned char* layer_out = frame.layers[v];
      const cv::Vec2f* ray = &rays_[static_cast<std::size_t>(v) * k.width * samples];
      for (int u = 0; u < k.width; ++u) {
        float sum = 0.0f;
        int first_layer = -1;
        bool mixed = false;
        for (int q = 0; q < samples; ++q, ++ray) {
          // opticalToWorld(pose) * (x, y, 1); level poses keep the shorter form they always had.
          const double x = (*ray)[0], y = (*ray)[1];
          const SceneHit hit = scene.cast(origin, level ? cv::Vec3d(c * x + s * y, s * x - c * y, -1.0)
                                                        : rotation * cv::Vec3d(x, y, 1.0));
          sum += scene.shade(hit);
          const int code = hit.onWall() ? RenderedFrame::kWallLayers + hit.layer : hit.layer;
          if (first_layer < 0) first_layer = code;
          mixed = mixed || code != first_layer;
        }
        out[u] = sum / static_cast<float>(samples);
        layer_out[u] = mixed ? RenderedFrame::kMixedLayers : static_cast<unsigned char>(first_layer);
      }
    }
  });
  return frame;
}

}  // namespace sim
}  // namespace oefmt
