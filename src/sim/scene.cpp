// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/sim/scene.h"

#include <algorithm>
#include <cmath>


#include "oefmt/io/dataset.h"
#include "oefmt/error.h"
#include "oefmt/io/image_decoding.h"
#include "oefmt/registration/image_prep.h"
#include "oefmt/sim/texture.h"

namespace oefmt {
namespace sim {
namespace {

// splitmix64's finaliser: a well-mixed 64-bit hash, the same on every machine.
std::uint64_t mix(std::uint64_t z) {
  z += 0x9E3779B97F4A7C15ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

// [0, 1) from the top 53 bits.
double unit(std::uint64_t h) { return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0); }

enum Purpose : std::uint64_t { kTerraceLevel = 1, kTerraceAzimuth = 2, kCellFilled = 3 };
constexpr int kDirections = 256;

long long floorIndex(double value) { return static_cast<long long>(std::floor(value)); }

// floor(a / b) for b > 0, exact in integers.
long long floorDivide(long long a, long long b) { return a >= 0 ? a / b : -((-a + b - 1) / b); }

cv::Mat1f textureFromFile(const std::string& path) {
  cv::Mat image;
  try {
    image = readImageFile(path);
  } catch (const InputError& e) {
    throw DatasetError(std::string("texture: ") + e.what());  // names the file
  }
  cv::Mat1f grey = toGreyFloat(image);
  const int margin = std::max(4, std::min(grey.cols, grey.rows) / 8);
  if (grey.cols <= 2 * margin + 8 || grey.rows <= 2 * margin + 8) {
    throw InputError("texture image '" + path + "' is too small");
  }
  cv::Mat1f tile = makeTileable(grey, margin);
  cv::normalize(tile, tile, 0.0, 1.0, cv::NORM_MINMAX);
  return tile;
}

// A layer's procedural texture of a resolved style (not kMixed).
cv::Mat1f layerTexture(TextureStyle style, int size, std::uint32_t seed, double feature_texels,
                       double pattern_texels) {
  switch (style) {
    case TextureStyle::kNatural: return naturalTexture(size, seed, feature_texels);
    case TextureStyle::kBrick: return brickTexture(size, seed, pattern_texels);
    case TextureStyle::kTiles: return tileTexture(size, seed, pattern_texels);
    case TextureStyle::kNoise:
      // Plain noise is smooth at the coarse scale: finer structures keep it rich in detail.
      return tileableTexture(size, seed, style, std::max(2.0, feature_texels / 4.0));
    default: return tileableTexture(size, seed, style, feature_texels);
  }
}

// How much darker a wall is than a top of the same texture, in standard deviations of that
// texture: walls are lit from the east-south-east, tops from straight above, so walls facing
// different ways differ. In units of the texture's contrast so that a dull scene (--contrast)
// gets dull walls too: fixed factors would turn its walls into its strongest edges.
float wallDarkening(Facing facing) {
  switch (facing) {
    case Facing::kEast: return 0.7f;
    case Facing::kSouth: return 0.95f;
    case Facing::kNorth: return 1.25f;
    case Facing::kWest: return 1.45f;
    case Facing::kUp: break;
  }
  return 0.0f;
}

}  // namespace

void SceneConfig::validate() const {
  requireInput(cell_size > 0.0 && std::isfinite(cell_size), "scene: cell_size must be > 0");
  requireInput(terrace_cells >= 1, "scene: terrace_cells must be >= 1");
  requireInput(gap >= 0.0 && gap < 0.5, "scene: gap must be in [0, 0.5)");
  requireInput(fill >= 0.0 && fill <= 1.0, "scene: fill must be in [0, 1]");
  requireInput(texel > 0.0 && std::isfinite(texel), "scene: texel must be > 0");
  requireInput(texture_size >= 64, "scene: texture_size must be >= 64");
  requireInput(feature_texels >= 2.0, "scene: feature_texels must be >= 2");
  for (double pattern : pattern_texels) {
    requireInput(pattern > 0.0 && std::isfinite(pattern), "scene: pattern_texels must be > 0");
  }
  requireInput(texture_std >= 0.0 && texture_std <= 0.5, "scene: texture_std must be in [0, 0.5]");
  // The renderer's layer map codes level k as k and its walls as 128 + k.
  requireInput(levels.size() <= 126, "scene: at most 126 raised levels");
  double shares = 0.0;
  for (const BlockLevel& level : levels) {
    requireInput(level.height > 0.0 && std::isfinite(level.height), "scene: level heights must be > 0");
    requireInput(level.incline_deg >= 0.0 && level.incline_deg < 45.0, "scene: level inclines must be in [0, 45) deg");
    requireInput(level.share >= 0.0, "scene: level shares must be >= 0");
    shares += level.share;
  }
  requireInput(shares <= 1.0 + 1e-9, "scene: the levels' shares must add up to at most 1");
}

double SceneConfig::levelReach(const BlockLevel& level) const {
  const double terrace_half_diagonal = cell_size * terrace_cells * std::sqrt(0.5);
  return std::tan(level.incline_deg * CV_PI / 180.0) * terrace_half_diagonal;
}

double SceneConfig::highestTop() const {
  double top = 0.0;
  for (const BlockLevel& level : levels) top = std::max(top, level.height + levelReach(level));
  return top;
}

double SceneConfig::patternTexels(int layer) const {
  if (pattern_texels.empty()) return 64.0;
  return pattern_texels[std::min(static_cast<std::size_t>(layer), pattern_texels.size() - 1)];
}

Scene::Scene(const SceneConfig& config)
    : config_(config), seed_hash_(mix(config.seed)) {
  config_.validate();
  terrace_side_ = config_.cell_size * config_.terrace_cells;
  inverse_cell_ = 1.0 / config_.cell_size;
  inverse_terrace_side_ = 1.0 / terrace_side_;
  inverse_texel_ = 1.0 / config_.texel;
  highest_top_ = config_.highestTop();
  const int layers = static_cast<int>(config_.levels.size()) + 1;
  textures_.resize(layers);
  // Layers in parallel: the textures are the slowest part of setting up a flight.
  cv::parallel_for_(cv::Range(0, layers), [&](const cv::Range& range) {
    for (int layer = range.start; layer < range.end; ++layer) {
      const bool from_file = layer < static_cast<int>(config_.texture_files.size()) &&
                             !config_.texture_files[layer].empty();
      const int size = layer == 0 ? config_.texture_size : std::max(64, config_.texture_size / 2);
      textures_[layer] = from_file ? textureFromFile(config_.texture_files[layer])
                                   : layerTexture(layerTextureStyle(config_.texture_styles, layer), size,
                                                  config_.seed * 7919u + layer, config_.feature_texels,
                                                  config_.patternTexels(layer));
      if (config_.texture_std > 0.0) textures_[layer] = withContrast(textures_[layer], config_.texture_std);
    }
  });
  for (const cv::Mat1f& texture : textures_) {
    inverse_texture_size_.emplace_back(1.0 / texture.cols, 1.0 / texture.rows);
    cv::Scalar mean, std;
    cv::meanStdDev(texture, mean, std);
    texture_std_.push_back(static_cast<float>(std[0]));
  }
  double bound = 0.0;
  for (const BlockLevel& level : config_.levels) {
    level_reach_.push_back(config_.levelReach(level));
    level_slope_.push_back(std::tan(level.incline_deg * CV_PI / 180.0));
    bound += level.share;
    share_bounds_.push_back(bound);
  }
  for (int k = 0; k < kDirections; ++k) {
    const double azimuth = 2.0 * CV_PI * (k + 0.5) / kDirections;
    directions_.emplace_back(std::cos(azimuth), std::sin(azimuth));
  }
  tabulate();
}

std::uint64_t Scene::hash(long long i, long long j, std::uint64_t purpose) const {
  return mix(seed_hash_ ^ mix(static_cast<std::uint64_t>(i) * 0xD1B54A32D192ED03ULL ^
                              static_cast<std::uint64_t>(j) * 0xABC98388FB8FAC03ULL ^ purpose));
}

int Scene::computeTerraceLevel(long long ti, long long tj) const {
  const double u = unit(hash(ti, tj, kTerraceLevel));
  for (std::size_t l = 0; l < share_bounds_.size(); ++l) {
    if (u < share_bounds_[l]) return static_cast<int>(l);
  }
  return -1;
}

int Scene::computeCellCode(long long ci, long long cj) const {
  if (unit(hash(ci, cj, kCellFilled)) >= config_.fill) return 0;
  return computeTerraceLevel(floorDivide(ci, config_.terrace_cells), floorDivide(cj, config_.terrace_cells)) + 1;
}

void Scene::tabulate() {
  const cv::Rect2d& r = config_.region;
  if (!(r.width > 0.0 && r.height > 0.0)) return;
  Layout& t = layout_;
  const double cells = (r.width / config_.cell_size + 3.0) * (r.height / config_.cell_size + 3.0);
  if (!(cells < 64e6)) return;  // too large to be worth it: compute on the fly
  t.cell_i0 = floorIndex(r.x / config_.cell_size) - 1;
  t.cell_j0 = floorIndex(r.y / config_.cell_size) - 1;
  t.cell_cols = static_cast<int>(floorIndex((r.x + r.width) / config_.cell_size) + 2 - t.cell_i0);
  t.cell_rows = static_cast<int>(floorIndex((r.y + r.height) / config_.cell_size) + 2 - t.cell_j0);
  t.cell_code.resize(static_cast<std::size_t>(t.cell_cols) * t.cell_rows);
  for (int j = 0; j < t.cell_rows; ++j) {
    for (int i = 0; i < t.cell_cols; ++i) {
      t.cell_code[static_cast<std::size_t>(j) * t.cell_cols + i] =
          static_cast<signed char>(computeCellCode(t.cell_i0 + i, t.cell_j0 + j));
    }
  }
  t.terrace_i0 = floorIndex(r.x / terrace_side_) - 1;
  t.terrace_j0 = floorIndex(r.y / terrace_side_) - 1;
  t.terrace_cols = static_cast<int>(floorIndex((r.x + r.width) / terrace_side_) + 2 - t.terrace_i0);
  t.terrace_rows = static_cast<int>(floorIndex((r.y + r.height) / terrace_side_) + 2 - t.terrace_j0);
  for (int j = 0; j < t.terrace_rows; ++j) {
    for (int i = 0; i < t.terrace_cols; ++i) {
      t.terrace_level.push_back(static_cast<signed char>(computeTerraceLevel(t.terrace_i0 + i, t.terrace_j0 + j)));
      t.terrace_direction.push_back(
          static_cast<unsigned char>(hash(t.terrace_i0 + i, t.terrace_j0 + j, kTerraceAzimuth) % kDirections));
    }
  }
}

int Scene::terraceLevel(long long ti, long long tj) const {
  const long long i = ti - layout_.terrace_i0, j = tj - layout_.terrace_j0;
  if (i >= 0 && j >= 0 && i < layout_.terrace_cols && j < layout_.terrace_rows) {
    return layout_.terrace_level[static_cast<std::size_t>(j) * layout_.terrace_cols + i];
  }
  return computeTerraceLevel(ti, tj);
}

cv::Vec2d Scene::terraceSlope(long long ti, long long tj, int level) const {
  if (level_slope_[level] == 0.0) return {0.0, 0.0};
  const long long i = ti - layout_.terrace_i0, j = tj - layout_.terrace_j0;
  const bool tabulated = i >= 0 && j >= 0 && i < layout_.terrace_cols && j < layout_.terrace_rows;
  const std::size_t direction = tabulated ? layout_.terrace_direction[static_cast<std::size_t>(j) * layout_.terrace_cols + i]
                                          : hash(ti, tj, kTerraceAzimuth) % kDirections;
  return level_slope_[level] * directions_[direction];
}

// Inline: the wall walk calls it for every cell it crosses.
inline int Scene::cellCode(long long ci, long long cj) const {
  const long long i = ci - layout_.cell_i0, j = cj - layout_.cell_j0;
  if (i >= 0 && j >= 0 && i < layout_.cell_cols && j < layout_.cell_rows) {
    return layout_.cell_code[static_cast<std::size_t>(j) * layout_.cell_cols + i];
  }
  return computeCellCode(ci, cj);
}

int Scene::topAt(double x, double y, long long* ti, long long* tj) const {
  const double cx = x * inverse_cell_, cy = y * inverse_cell_;
  const double fci = std::floor(cx), fcj = std::floor(cy);
  const double fx = cx - fci, fy = cy - fcj;
  if (fx < config_.gap || fx > 1.0 - config_.gap || fy < config_.gap || fy > 1.0 - config_.gap) return 0;
  const long long ci = static_cast<long long>(fci), cj = static_cast<long long>(fcj);
  *ti = floorDivide(ci, config_.terrace_cells);
  *tj = floorDivide(cj, config_.terrace_cells);
  return cellCode(ci, cj);
}

double Scene::topHeight(int level, long long ti, long long tj, double x, double y) const {
  const cv::Vec2d slope = terraceSlope(ti, tj, level);
  return config_.levels[level].height + slope[0] * (x - (ti + 0.5) * terrace_side_) +
         slope[1] * (y - (tj + 0.5) * terrace_side_);
}

int Scene::layerAt(double x, double y, double* height) const {
  long long ti = 0, tj = 0;
  const int code = topAt(x, y, &ti, &tj);
  if (height) *height = 0.0;
  if (code == 0) return 0;
  if (height) *height = topHeight(code - 1, ti, tj, x, y);
  return code;
}

SceneHit Scene::cast(const cv::Vec3d& o, const cv::Vec3d& d) const {
  const double inverse_descent = -1.0 / d[2];
  SceneHit best;
  best.t = o[2] * inverse_descent;
  best.x = o[0] + best.t * d[0];
  best.y = o[1] + best.t * d[1];
  const double horizontal = std::sqrt(d[0] * d[0] + d[1] * d[1]) * inverse_descent;
  for (int l = 0; l < static_cast<int>(config_.levels.size()); ++l) {
    const double h = config_.levels[l].height;
    const double t0 = (o[2] - h) * inverse_descent;
    if (t0 <= 0.0) continue;
    const double x0 = o[0] + t0 * d[0], y0 = o[1] + t0 * d[1];
    if (level_reach_[l] == 0.0) {  // flat: the crossing of z = h is the only candidate
      long long ti = 0, tj = 0;
      if (t0 < best.t && topAt(x0, y0, &ti, &tj) == l + 1) {
        best.layer = l + 1;
        best.t = t0;
        best.x = x0;
        best.y = y0;
      }
      continue;
    }
    // Any top of this level lies within level_reach_ of height h, so the ray meets it within
    // `reach` (horizontally) of where it crosses z = h: only terraces that near can be hit.
    const double reach = level_reach_[l] * horizontal;
    const long long ti_end = floorIndex((x0 + reach) * inverse_terrace_side_);
    const long long tj_end = floorIndex((y0 + reach) * inverse_terrace_side_);
    for (long long ti = floorIndex((x0 - reach) * inverse_terrace_side_); ti <= ti_end; ++ti) {
      for (long long tj = floorIndex((y0 - reach) * inverse_terrace_side_); tj <= tj_end; ++tj) {
        if (terraceLevel(ti, tj) != l) continue;
        const cv::Vec2d slope = terraceSlope(ti, tj, l);
        const double centre_x = (ti + 0.5) * terrace_side_, centre_y = (tj + 0.5) * terrace_side_;
        // o.z + t d.z = h + sx (o.x + t d.x - cx) + sy (o.y + t d.y - cy)
        const double denominator = d[2] - slope[0] * d[0] - slope[1] * d[1];
        if (denominator >= 0.0) continue;
        const double t = (h + slope[0] * (o[0] - centre_x) + slope[1] * (o[1] - centre_y) - o[2]) / denominator;
        if (t <= 0.0 || t >= best.t) continue;
        const double x = o[0] + t * d[0], y = o[1] + t * d[1];
        long long hit_ti = 0, hit_tj = 0;
        if (topAt(x, y, &hit_ti, &hit_tj) != l + 1 || hit_ti != ti || hit_tj != tj) continue;
        best.layer = l + 1;
        best.t = t;
        best.x = x;
        best.y = y;
      }
    }
  }
  best.z = o[2] + best.t * d[2];
  if (config_.walls && !config_.levels.empty()) castWalls(o, d, &best);
  return best;
}

void Scene::castWalls(const cv::Vec3d& o, const cv::Vec3d& d, SceneHit* best) const {
  // Nothing stands above the highest top: walk the cells under the ray from where it descends
  // through that height to its hit so far (a top or the ground), nearest first, so the first
  // wall met is the nearest one.
  const double t_start = std::max(0.0, (o[2] - highest_top_) / -d[2]);
  if (!(t_start < best->t)) return;
  const double cell = config_.cell_size;
  long long ci = floorIndex((o[0] + t_start * d[0]) * inverse_cell_);
  long long cj = floorIndex((o[1] + t_start * d[1]) * inverse_cell_);
  // Reciprocals: the walk multiplies instead of dividing (an axis the ray does not move along
  // never reaches a boundary).
  const double inverse_x = d[0] != 0.0 ? 1.0 / d[0] : 0.0, inverse_y = d[1] != 0.0 ? 1.0 / d[1] : 0.0;
  // The ray's parameter range inside [low, high] along one axis (all of it, or none, for an
  // axis it does not move along).
  const auto slab = [](double origin, double direction, double inverse, double low, double high, double* in,
                       double* out) {
    if (direction == 0.0) {
      *in = origin >= low && origin <= high ? -HUGE_VAL : HUGE_VAL;
      *out = HUGE_VAL;
      return;
    }
    const double a = (low - origin) * inverse, b = (high - origin) * inverse;
    *in = std::min(a, b);
    *out = std::max(a, b);
  };
  const double inset = config_.gap * cell;
  // Whether the ray enters the block of cell (ci, cj) through a side wall before *best; if so
  // *best becomes that wall.
  const auto wall = [&](long long i, long long j) {
    const int code = cellCode(i, j);
    if (code == 0) return false;
    // The block's inset square: the ray enters it at t_in through the wall of the later slab.
    double tx_in = 0.0, tx_out = 0.0, ty_in = 0.0, ty_out = 0.0;
    slab(o[0], d[0], inverse_x, i * cell + inset, (i + 1) * cell - inset, &tx_in, &tx_out);
    slab(o[1], d[1], inverse_y, j * cell + inset, (j + 1) * cell - inset, &ty_in, &ty_out);
    const double t_in = std::max(tx_in, ty_in);
    if (!(t_in < std::min(tx_out, ty_out) && t_in > 0.0 && t_in < best->t)) return false;
    const double x = o[0] + t_in * d[0], y = o[1] + t_in * d[1], z = o[2] + t_in * d[2];
    const int level = code - 1;
    // Above the top's edge there, the ray passes over the wall (and may land on the top).
    const double edge = level_slope_[level] == 0.0 ? config_.levels[level].height
                                                   : topHeight(level, floorDivide(i, config_.terrace_cells),
                                                               floorDivide(j, config_.terrace_cells), x, y);
    if (z > edge) return false;
    best->layer = code;
    best->t = t_in;
    best->x = x;
    best->y = y;
    best->z = z;
    best->facing = tx_in >= ty_in ? (d[0] > 0.0 ? Facing::kWest : Facing::kEast)
                                  : (d[1] > 0.0 ? Facing::kSouth : Facing::kNorth);
    return true;
  };
  if (ci == floorIndex(best->x * inverse_cell_) && cj == floorIndex(best->y * inverse_cell_)) {
    // The most common case, cheaply: the ray stays over one cell. A ray that lands on that
    // cell's top has not passed its walls (it crosses the top's plane once, from above).
    if (best->layer == 0) wall(ci, cj);
    return;
  }
  const int step_i = d[0] > 0.0 ? 1 : -1, step_j = d[1] > 0.0 ? 1 : -1;
  double next_x = d[0] != 0.0 ? ((ci + (step_i > 0 ? 1 : 0)) * cell - o[0]) * inverse_x : HUGE_VAL;
  double next_y = d[1] != 0.0 ? ((cj + (step_j > 0 ? 1 : 0)) * cell - o[1]) * inverse_y : HUGE_VAL;
  const double delta_x = d[0] != 0.0 ? cell * std::fabs(inverse_x) : HUGE_VAL;
  const double delta_y = d[1] != 0.0 ? cell * std::fabs(inverse_y) : HUGE_VAL;
  for (double t_cell = t_start; t_cell < best->t;) {
    if (wall(ci, cj)) return;
    if (next_x < next_y) {
      t_cell = next_x;
      next_x += delta_x;
      ci += step_i;
    } else {
      t_cell = next_y;
      next_y += delta_y;
      cj += step_j;
    }
  }
}

float Scene::shade(const SceneHit& hit) const {
  if (!hit.onWall()) return sample(hit.layer, hit.x, hit.y);
  // The texture stands upright on the wall: its rows along z, its columns along the wall.
  const bool along_y = hit.facing == Facing::kEast || hit.facing == Facing::kWest;
  const float value = sample(hit.layer, along_y ? hit.y : hit.x, hit.z);
  return std::max(0.0f, value - wallDarkening(hit.facing) * texture_std_[hit.layer]);
}

float Scene::sample(int layer, double x, double y) const {
  const cv::Mat1f& texture = textures_[layer];
  const double w = texture.cols, h = texture.rows;
  // Texture rows run southwards so that a texture looks upright in a yaw-0 image.
  double u = x * inverse_texel_, v = -y * inverse_texel_;
  u -= std::floor(u * inverse_texture_size_[layer][0]) * w;
  v -= std::floor(v * inverse_texture_size_[layer][1]) * h;
  if (u < 0.0) u += w;  // rounding of the reciprocal
  if (v < 0.0) v += h;
  int u0 = static_cast<int>(u), v0 = static_cast<int>(v);
  const float fu = static_cast<float>(u - u0), fv = static_cast<float>(v - v0);
  if (u0 >= texture.cols) u0 -= texture.cols;  // rounding at the wrap
  if (v0 >= texture.rows) v0 -= texture.rows;
  const int u1 = u0 + 1 == texture.cols ? 0 : u0 + 1;
  const int v1 = v0 + 1 == texture.rows ? 0 : v0 + 1;
  const float* r0 = texture[v0];
  const float* r1 = texture[v1];
  const float top = r0[u0] + fu * (r0[u1] - r0[u0]);
  const float bottom = r1[u0] + fu * (r1[u1] - r1[u0]);
  return top + fv * (bottom - top);
}

}  // namespace sim
}  // namespace oefmt
