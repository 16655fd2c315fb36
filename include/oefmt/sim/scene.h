// SPDX-License-Identifier: GPL-3.0-or-later
// The simulated multi-depth scene: a textured ground plane (z = 0) and raised block tops at
// further levels, laid out on a grid of square cells grouped into terraces.
//
// Each terrace (terrace_cells x terrace_cells cells) belongs to one raised level or to none (chosen
// by a hash of the seed, weighted by the levels' shares); in a raised terrace each cell carries a
// block top with probability `fill`, inset by `gap` of the cell on every side so that gaps show
// the deeper layers. An inclined level tilts each terrace's tops as one plane through the level's
// height at the terrace centre, downhill in a random direction per terrace. Without `walls` tops
// are zero-thickness slabs; with it each top is the lid of a solid prism standing on the ground,
// whose four vertical side walls are surfaces too.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/sim/texture.h"

namespace oefmt {
namespace sim {

/// A raised level of block tops.
struct BlockLevel {
  double height = 2.0;       ///< above the ground at the terrace centres [m]
  double incline_deg = 0.0;  ///< tilt of the terrace planes [deg], 0 = flat
  double share = 0.35;       ///< fraction of terraces given to this level
};

struct SceneConfig {
  std::uint32_t seed = 1;
  double cell_size = 3.0;     ///< block grid pitch [m]
  int terrace_cells = 3;      ///< cells per side of a terrace
  double gap = 0.12;          ///< empty fraction of a cell on each side of its top
  double fill = 0.6;          ///< probability that a cell of a raised terrace has a top
  std::vector<BlockLevel> levels{{2.0, 0.0, 0.35}, {4.0, 6.0, 0.35}};
  double texel = 0.01;        ///< texture resolution [m per texel]
  int texture_size = 4096;    ///< side of the ground's procedural texture [texels] (raised
                              ///< levels: half); procedural textures tile seamlessly
  double feature_texels = 100.0;  ///< coarsest procedural structures [texels]
  /// Image file per layer (0 = ground, k = levels[k - 1]); empty or missing = procedural.
  std::vector<std::string> texture_files;
  /// Procedural style per layer (ground first); beyond the list the last one; empty = kMixed.
  std::vector<TextureStyle> texture_styles;
  /// Brick length / tile side per layer [texels] (ground first; beyond the list the last one;
  /// empty: 64), for the brick and tiles styles.
  std::vector<double> pattern_texels;
  /// Standard deviation every layer's texture is rescaled to (intensity units, around mid grey
  /// 0.5, clipped to [0, 1]); 0 = as made.
  double texture_std = 0.0;
  /// Tops are lids of solid prisms standing on the ground; their side walls are rendered.
  bool walls = false;
  /// World x-y area [m] whose block layout is tabulated for speed; outside it the same layout is
  /// computed on the fly (the images do not depend on it). Empty: nothing tabulated.
  cv::Rect2d region;

  /// Throws InputError naming the first invalid field.
  void validate() const;
  /// Largest |top height - level height| of a level's tops [m] (from its incline).
  double levelReach(const BlockLevel& level) const;
  /// Height of the highest point of any top [m] (0 without raised levels).
  double highestTop() const;
  /// pattern_texels of a layer (see there).
  double patternTexels(int layer) const;
};

/// Which way the surface a ray hits faces: up (a top or the ground) or one of the four
/// directions of a prism's side walls (world axes: east = +x, north = +y).
enum class Facing : unsigned char { kUp, kEast, kWest, kNorth, kSouth };

/// Where a ray meets the scene.
struct SceneHit {
  int layer = 0;     ///< 0 = ground, k = levels[k - 1]
  double t = 0.0;    ///< ray parameter of the hit (distance for a unit ray)
  double x = 0.0;    ///< world position of the hit [m]
  double y = 0.0;
  double z = 0.0;
  Facing facing = Facing::kUp;  ///< anything but kUp: a side wall of a top of `layer`
  bool onWall() const { return facing != Facing::kUp; }
};

class Scene {
 public:
  /// Builds the textures (procedural from the seed, or read from texture_files).
  /// Throws InputError for an invalid config, DatasetError for an unreadable texture file.
  explicit Scene(const SceneConfig& config);

  const SceneConfig& config() const { return config_; }
  int layerCount() const { return static_cast<int>(textures_.size()); }
  const cv::Mat1f& texture(int layer) const { return textures_[layer]; }

  /// First surface along origin + t * direction (direction pointing down, z < 0).
  SceneHit cast(const cv::Vec3d& origin, const cv::Vec3d& direction) const;

  /// Bilinear texture value of `layer` at world x-y (textures repeat).
  float sample(int layer, double x, double y) const;

  /// The intensity a hit shows: on a top or the ground its layer's texture at x-y; on a wall the
  /// layer's texture at (horizontal position along the wall, z), darkened by 0.7 (facing east),
  /// 0.95 (south), 1.25 (north) or 1.45 (west) times the texture's standard deviation, at least 0.
  float shade(const SceneHit& hit) const;

  /// The raised level (1-based layer) whose top covers world x-y, or 0 for bare ground; with
  /// the top's height in *height (0 for the ground).
  int layerAt(double x, double y, double* height = nullptr) const;

 private:
  /// Block layout by cell or terrace index, tabulated over config_.region.
  struct Layout {
    long long cell_i0 = 0, cell_j0 = 0;
    int cell_cols = 0, cell_rows = 0;
    std::vector<signed char> cell_code;  ///< 0: no top, l + 1: a top of level l
    long long terrace_i0 = 0, terrace_j0 = 0;
    int terrace_cols = 0, terrace_rows = 0;
    std::vector<signed char> terrace_level;      ///< -1: ground only
    std::vector<unsigned char> terrace_direction;
  };

  std::uint64_t hash(long long i, long long j, std::uint64_t purpose) const;
  int computeTerraceLevel(long long ti, long long tj) const;
  int computeCellCode(long long ci, long long cj) const;
  int terraceLevel(long long ti, long long tj) const;
  /// dz/dx, dz/dy of a terrace's plane for level l.
  cv::Vec2d terraceSlope(long long ti, long long tj, int level) const;
  /// The cell code (see Layout) of the cell under world x-y, 0 in the gaps between tops; sets the
  /// cell's terrace.
  int topAt(double x, double y, long long* ti, long long* tj) const;
  /// The cell code (see Layout) of cell (ci, cj), gaps included.
  int cellCode(long long ci, long long cj) const;
  /// Height of a level-l top of terrace (ti, tj) at world x-y [m].
  double topHeight(int level, long long ti, long long tj, double x, double y) const;
  /// Replaces *best by the first prism side wall along the ray before it, if any.
  void castWalls(const cv::Vec3d& origin, const cv::Vec3d& direction, SceneHit* best) const;
  void tabulate();

  SceneConfig config_;
  std::uint64_t seed_hash_;
  double terrace_side_;
  // Reciprocals: the per-ray code multiplies instead of dividing.
  double inverse_cell_;
  double inverse_terrace_side_;
  double inverse_texel_;
  std::vector<cv::Vec2d> inverse_texture_size_;  ///< per layer (1 / cols, 1 / rows)
  std::vector<cv::Mat1f> textures_;
  std::vector<float> texture_std_;    ///< per layer: its texture's standard deviation
  double highest_top_;
  std::vector<double> level_reach_;   ///< largest |top height - level height| per level [m]
  std::vector<double> level_slope_;   ///< tan(incline) per level
  std::vector<double> share_bounds_;  ///< cumulative shares: terrace hash below bound l -> level l
  std::vector<cv::Vec2d> directions_; ///< unit vectors for the terraces' downhill directions
  Layout layout_;
};

}  // namespace sim
}  // namespace oefmt
