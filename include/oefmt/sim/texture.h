// SPDX-License-Identifier: GPL-3.0-or-later
// Procedural textures for the flight simulator and the tests: deterministic for a seed.
#pragma once

#include <cstdint>

#include <opencv2/core.hpp>

namespace oefmt {
namespace sim {

enum class TextureStyle {
  kNoise,   ///< multi-octave value noise (fields, water, sand)
  kCells,   ///< noise plus random rectangles and discs (roofs, vehicles, rocks)
  kStripes, ///< noise plus oriented stripes of several periods (fields, roads)
};

/// A width x height texture with values in [0, 1]. Same seed, same texture, on every machine.
/// feature_px is the size of the coarsest structures [px].
cv::Mat1f proceduralTexture(cv::Size size, std::uint32_t seed,
                            TextureStyle style = TextureStyle::kCells, double feature_px = 48.0);

/// Makes `source` periodic without a seam: the last `margin` columns and rows are cross-faded into
/// the first ones (weights that keep the variance of independent noise). The result is
/// (width - margin) x (height - margin) and tiles seamlessly. Throws InputError when margin < 1
/// or the source is not larger than 2 * margin.
cv::Mat1f makeTileable(const cv::Mat1f& source, int margin);

/// A size x size proceduralTexture that tiles seamlessly (made from a larger one by makeTileable).
cv::Mat1f tileableTexture(int size, std::uint32_t seed, TextureStyle style, double feature_px);

}  // namespace sim
}  // namespace oefmt
