// SPDX-License-Identifier: GPL-3.0-or-later
// Procedural textures for the flight simulator and the tests: deterministic for a seed.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/enum_names.h"

namespace oefmt {
namespace sim {

enum class TextureStyle {
  kNoise,   ///< multi-octave value noise (fields, water, sand)
  kCells,   ///< noise plus random rectangles and discs (roofs, vehicles, rocks)
  kStripes, ///< noise plus oriented stripes of several periods (fields, roads)
  kNatural, ///< photo-like: 1/f amplitude spectrum with random phases, plus soft patches
  kBrick,   ///< strictly periodic running-bond brick wall (identical bricks)
  kTiles,   ///< strictly periodic square tiles with grout lines and a motif
  /// Not a texture: a scene's default per-layer choice, kCells, kStripes, kNoise, kCells, ...
  /// for the ground, level 1, level 2, ... (each layer looks different from its neighbours).
  kMixed,
};

/// The command line's spelling of each style (parseEnum reads it).
inline constexpr EnumName<TextureStyle> kTextureStyleNames[] = {
    {TextureStyle::kMixed, "mixed"},     {TextureStyle::kCells, "cells"}, {TextureStyle::kStripes, "stripes"},
    {TextureStyle::kNoise, "noise"},     {TextureStyle::kNatural, "natural"},
    {TextureStyle::kBrick, "brick"},     {TextureStyle::kTiles, "tiles"}};
inline const char* toString(TextureStyle style) { return enumName(kTextureStyleNames, style); }

/// The style of a scene's layer (0 ground, k level k): styles[layer], the last style beyond the
/// list, kMixed for an empty list; kMixed resolved to the layer's mixed choice.
TextureStyle layerTextureStyle(const std::vector<TextureStyle>& styles, int layer);

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
/// Styles kNoise, kCells, kStripes only (the others tile by construction: see below).
cv::Mat1f tileableTexture(int size, std::uint32_t seed, TextureStyle style, double feature_px);

/// A size x size photo-like texture: a power-law amplitude spectrum (1/f above the frequency of
/// structures about 8 * feature_px across, flat below it) with random phases, synthesised by an
/// inverse FFT so that it tiles seamlessly, plus soft-edged patches of other brightness (fields,
/// shadows) drawn with wrap-around. Mean 0.5, std 0.15 (about the other styles' contrast),
/// clipped to [0, 1].
cv::Mat1f naturalTexture(int size, std::uint32_t seed, double feature_px);

/// The running bond of brickTexture for a brick about brick_px long: bricks of (length, height)
/// texels, height even and length 3 * height, rows offset by half a brick. The pattern repeats
/// after (length, 0), (length / 2, height) and (0, 2 * height).
cv::Size brickSize(double brick_px);
/// A strictly periodic brick wall: identical bricks (one shading, a little fixed detail from the
/// seed that is the same in every brick), darker mortar lines, rows offset by half a brick. Its
/// side is the multiple of two brick lengths (= six rows) nearest to `size`, so it tiles
/// seamlessly and repeats exactly in the world.
cv::Mat1f brickTexture(int size, std::uint32_t seed, double brick_px);

/// The side [texels] of tileTexture's tiles for tiles about tile_px wide (even, >= 12).
int tileSide(double tile_px);
/// A strictly periodic square tiling: identical tiles (a disc and a small off-centre square as
/// motif, a little fixed detail from the seed) between darker grout lines. Its side is the
/// multiple of the tile side nearest to `size`.
cv::Mat1f tileTexture(int size, std::uint32_t seed, double tile_px);

/// `texture` shifted and scaled to mean 0.5 and standard deviation `std` (intensity units),
/// clipped to [0, 1] (which lowers the deviation of high-contrast textures a little). A constant
/// texture becomes plain mid grey.
cv::Mat1f withContrast(const cv::Mat1f& texture, double std);

}  // namespace sim
}  // namespace oefmt
