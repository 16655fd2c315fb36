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

}  // namespace sim
}  // namespace oefmt
