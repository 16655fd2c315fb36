// SPDX-License-Identifier: GPL-3.0-or-later
// Views of a flat textured scene related by a known similarity (rotation, zoom, shift): test
// pairs with exact ground truth, and the pair demo.
#pragma once

#include <opencv2/core.hpp>

namespace oefmt {
namespace sim {

/// Motion of a view's content relative to a reference view of the same size n:
/// x_new - c = zoom * R(rotation) * (x_ref - c) + shift, with c = (n/2, n/2), image axes
/// (x right, y down) and R turning counter-clockwise on screen for rotation > 0.
struct ViewMotion {
  double rotation = 0.0;  ///< [rad]
  double zoom = 1.0;
  cv::Point2d shift;      ///< [px]
};

/// Renders an n x n view of `texture` centred on texture_centre, moved by `motion` (bicubic).
cv::Mat1f renderView(const cv::Mat1f& texture, cv::Point2d texture_centre, const ViewMotion& motion,
                     int n);

/// A two-depth scene: a background and raised blocks (foreground) with their own texture.
/// Each layer is moved by its own shift; the foreground's mask moves with it.
cv::Mat1f renderTwoLayerView(const cv::Mat1f& background, const cv::Mat1f& foreground,
                             const cv::Mat1f& foreground_mask, cv::Point2d texture_centre,
                             cv::Point2d background_shift, cv::Point2d foreground_shift, int n);

/// A block pattern mask (1 = foreground) of the given size, deterministic for a seed.
cv::Mat1f blockMask(cv::Size size, unsigned seed, double block_px, double fill_fraction);

}  // namespace sim
}  // namespace oefmt
