// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/sim/similarity_views.h"

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"
#include "oefmt/registration/warp.h"

namespace oefmt {
namespace sim {

cv::Mat1f renderView(const cv::Mat1f& texture, cv::Point2d texture_centre, const ViewMotion& motion,
                     int n) {
  if (texture.empty()) throw InputError("renderView: empty texture");
  if (!(motion.zoom > 0.0)) throw InputError("renderView: zoom must be > 0");
  // Inverse map: texture(tc + M^-1 (x_new - c - shift)), M = zoom * R(rotation).
  const double c = std::cos(motion.rotation) / motion.zoom;
  const double s = std::sin(motion.rotation) / motion.zoom;
  const cv::Point2d centre(imageCentre(n), imageCentre(n));
  const cv::Point2d origin = centre + motion.shift;
  cv::Matx23d inverse(c, -s, 0.0, s, c, 0.0);
  inverse(0, 2) = texture_centre.x - (c * origin.x - s * origin.y);
  inverse(1, 2) = texture_centre.y - (s * origin.x + c * origin.y);
  cv::Mat1f view;
  cv::warpAffine(texture, view, inverse, cv::Size(n, n), cv::INTER_CUBIC | cv::WARP_INVERSE_MAP,
                 cv::BORDER_REFLECT);
  return view;
}

cv::Mat1f renderTwoLayerView(const cv::Mat1f& background, const cv::Mat1f& foreground,
                             const cv::Mat1f& foreground_mask, cv::Point2d texture_centre,
                             cv::Point2d background_shift, cv::Point2d foreground_shift, int n) {
  ViewMotion back;
  back.shift = background_shift;
  ViewMotion front;
  front.shift = foreground_shift;
  const cv::Mat1f b = renderView(background, texture_centre, back, n);
  const cv::Mat1f f = renderView(foreground, texture_centre, front, n);
  const cv::Mat1f alpha = renderView(foreground_mask, texture_centre, front, n);
  cv::Mat1f view(n, n);
  for (int r = 0; r < n; ++r) {
    for (int col = 0; col < n; ++col) {
      const float a = std::min(1.0f, std::max(0.0f, alpha(r, col)));
      view(r, col) = a * f(r, col) + (1.0f - a) * b(r, col);
    }
  }
  return view;
}

cv::Mat1f blockMask(cv::Size size, unsigned seed, double block_px, double fill_fraction) {
  cv::RNG rng(seed);
  cv::Mat1f mask(size, 0.0f);
  const int cells_x = static_cast<int>(std::ceil(size.width / block_px));
  const int cells_y = static_cast<int>(std::ceil(size.height / block_px));
  for (int y = 0; y < cells_y; ++y) {
    for (int x = 0; x < cells_x; ++x) {
      if (rng.uniform(0.0, 1.0) >= fill_fraction) continue;
      const int margin = static_cast<int>(block_px * 0.15);
      const cv::Rect cell(static_cast<int>(x * block_px) + margin, static_cast<int>(y * block_px) + margin,
                          static_cast<int>(block_px) - 2 * margin, static_cast<int>(block_px) - 2 * margin);
      cv::rectangle(mask, cell, cv::Scalar(1.0), cv::FILLED);
    }
  }
  return mask;
}

}  // namespace sim
}  // namespace oefmt
