// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/sim/texture.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"

namespace oefmt {
namespace sim {
namespace {

// Value noise: random values on a coarse grid, bicubically enlarged, octaves of halving size.
void addValueNoise(cv::Mat1f& out, cv::RNG& rng, double feature_px) {
  double cell = feature_px;
  double amplitude = 1.0;
  while (cell >= 1.5) {
    const int grid_w = static_cast<int>(std::ceil(out.cols / cell)) + 3;
    const int grid_h = static_cast<int>(std::ceil(out.rows / cell)) + 3;
    cv::Mat1f grid(grid_h, grid_w);
    rng.fill(grid, cv::RNG::UNIFORM, -amplitude, amplitude);
    cv::Mat1f big;
    cv::resize(grid, big, cv::Size(), cell, cell, cv::INTER_CUBIC);
    out += big(cv::Rect(static_cast<int>(cell), static_cast<int>(cell), out.cols, out.rows));
    cell /= 2.0;
    amplitude *= 0.6;
  }
}

void addCells(cv::Mat1f& out, cv::RNG& rng, double feature_px) {
  const int count = static_cast<int>(out.total() / (feature_px * feature_px) * 3.0) + 1;
  for (int i = 0; i < count; ++i) {
    // One draw per statement: the order in which a call's arguments are evaluated is
    // unspecified (g++ drew y first, clang++ x), so the same seed gave other textures.
    const int y = rng.uniform(0, out.rows);
    const int x = rng.uniform(0, out.cols);
    const cv::Point centre(x, y);
    const double value = rng.uniform(-1.5, 1.5);
    const int extent = std::max(2, static_cast<int>(rng.uniform(0.1, 0.6) * feature_px));
    if (rng.uniform(0, 2) == 0) {
      const int w = extent, h = std::max(2, static_cast<int>(extent * rng.uniform(0.4, 1.6)));
      cv::rectangle(out, cv::Rect(centre.x - w / 2, centre.y - h / 2, w, h), cv::Scalar(value),
                    cv::FILLED, cv::LINE_AA);
    } else {
      cv::circle(out, centre, extent / 2, cv::Scalar(value), cv::FILLED, cv::LINE_AA);
    }
  }
}

void addStripes(cv::Mat1f& out, cv::RNG& rng, double feature_px) {
  for (int band = 0; band < 3; ++band) {
    const double angle = rng.uniform(0.0, CV_PI);
    const double period = feature_px * rng.uniform(0.15, 0.6);
    const double ca = std::cos(angle), sa = std::sin(angle);
    const double amplitude = rng.uniform(0.3, 0.8);
    for (int r = 0; r < out.rows; ++r) {
      float* row = out[r];
      for (int c = 0; c < out.cols; ++c) {
        row[c] += static_cast<float>(amplitude * std::sin(2.0 * CV_PI * (c * ca + r * sa) / period));
      }
    }
  }
}

// Smooth 0 -> 1 step of x over [0, 1] (clamped): anti-aliased edges.
float smoothStep(double x) {
  const double c = std::min(1.0, std::max(0.0, x));
  return static_cast<float>(c * c * (3.0 - 2.0 * c));
}

// Adds soft-edged elliptic patches of other brightness (in units of the field's std), drawn with
// wrap-around so that the texture still tiles.
void addSoftPatches(cv::Mat1f& out, cv::RNG& rng, double feature_px) {
  const int n = out.rows;
  const int count = static_cast<int>(static_cast<double>(n) * n / (feature_px * feature_px) * 0.35) + 1;
  for (int i = 0; i < count; ++i) {
    // One draw per statement (see addCells).
    const double centre_x = rng.uniform(0.0, static_cast<double>(n));
    const double centre_y = rng.uniform(0.0, static_cast<double>(n));
    const double a = feature_px * rng.uniform(0.3, 1.5);
    const double b = a * rng.uniform(0.25, 1.0);  // round ones and long ones (fields, ponds)
    const double angle = rng.uniform(0.0, CV_PI);
    const double magnitude = rng.uniform(0.6, 1.3);
    const double value = rng.uniform(0, 2) == 0 ? -magnitude : magnitude;
    const double edge = std::max(1.5, 0.12 * b);  // width of the soft rim [texels]
    const double ca = std::cos(angle), sa = std::sin(angle);
    const int reach = static_cast<int>(std::ceil(a + edge));
    for (int dy = -reach; dy <= reach; ++dy) {
      const int y = static_cast<int>(std::floor(centre_y)) + dy;
      float* row = out[((y % n) + n) % n];
      const double py = y + 0.5 - centre_y;
      for (int dx = -reach; dx <= reach; ++dx) {
        const int x = static_cast<int>(std::floor(centre_x)) + dx;
        const double px = x + 0.5 - centre_x;
        const double ex = (px * ca + py * sa) / a, ey = (-px * sa + py * ca) / b;
        // Approximate signed distance to the outline [texels], negative inside.
        const double distance = (std::sqrt(ex * ex + ey * ey) - 1.0) * b;
        row[((x % n) + n) % n] += static_cast<float>(value) * smoothStep(0.5 - distance / edge);
      }
    }
  }
}

// Shifts and scales to the given mean and std (no clipping).
void standardise(cv::Mat1f& texture, double mean, double std) {
  cv::Scalar m, s;
  cv::meanStdDev(texture, m, s);
  const double scale = s[0] > 1e-12 ? std / s[0] : 0.0;
  texture.convertTo(texture, CV_32F, scale, mean - scale * m[0]);
}

void clipToUnit(cv::Mat1f& texture) {
  cv::min(texture, 1.0, texture);
  cv::max(texture, 0.0, texture);
}

// Fixed detail inside a brick or tile: a gentle random relief (from the seed) of the given
// amplitude, the same in every brick or tile.
cv::Mat1f cellDetail(cv::Size size, cv::RNG& rng, double amplitude) {
  cv::Mat1f grid(std::max(2, size.height / 6), std::max(2, size.width / 6));
  rng.fill(grid, cv::RNG::UNIFORM, -amplitude, amplitude);
  cv::Mat1f detail;
  cv::resize(grid, detail, size, 0.0, 0.0, cv::INTER_LINEAR);
  return detail;
}

// Coverage [0, 1] of a brick or tile of `size` texels with a joint of half-width `joint` at texel
// (i, j): 1 inside, 0 on the joint, a one-texel ramp between.
float jointCoverage(int i, int j, cv::Size size, double joint) {
  const double x = i + 0.5, y = j + 0.5;
  const double edge = std::min(std::min(x, size.width - x), std::min(y, size.height - y));
  return smoothStep(edge - joint + 0.5);
}

// The square texture of side `side` that repeats `cell` with every row r of cells shifted right
// by row_shift(r) texels.
template <typename RowShift>
cv::Mat1f repeatCell(const cv::Mat1f& cell, int side, RowShift row_shift) {
  cv::Mat1f out(side, side);
  for (int y = 0; y < side; ++y) {
    const float* in = cell[y % cell.rows];
    const int shift = row_shift(y / cell.rows);
    float* row = out[y];
    for (int x = 0; x < side; ++x) row[x] = in[(x + shift) % cell.cols];
  }
  return out;
}

// The multiple of `period` nearest to `size`, at least one period.
int wholePeriods(int size, int period) {
  return std::max(1, static_cast<int>(std::lround(static_cast<double>(size) / period))) * period;
}

}  // namespace

TextureStyle layerTextureStyle(const std::vector<TextureStyle>& styles, int layer) {
  const TextureStyle style = styles.empty() ? TextureStyle::kMixed
                                            : styles[std::min(static_cast<std::size_t>(layer), styles.size() - 1)];
  if (style != TextureStyle::kMixed) return style;
  const TextureStyle mixed[] = {TextureStyle::kCells, TextureStyle::kStripes, TextureStyle::kNoise};
  return mixed[layer % 3];
}

cv::Mat1f proceduralTexture(cv::Size size, std::uint32_t seed, TextureStyle style,
                            double feature_px) {
  if (size.width <= 0 || size.height <= 0) throw InputError("proceduralTexture: empty size");
  if (!(feature_px >= 2.0)) throw InputError("proceduralTexture: feature_px must be >= 2");
  if (style != TextureStyle::kNoise && style != TextureStyle::kCells && style != TextureStyle::kStripes) {
    throw InputError(std::string("proceduralTexture: style ") + toString(style) + " is made elsewhere");
  }
  cv::RNG rng(0x9E3779B97F4A7C15ULL ^ seed);
  cv::Mat1f texture(size, 0.0f);
  addValueNoise(texture, rng, feature_px);
  if (style == TextureStyle::kCells) addCells(texture, rng, feature_px);
  if (style == TextureStyle::kStripes) addStripes(texture, rng, feature_px);
  cv::normalize(texture, texture, 0.0, 1.0, cv::NORM_MINMAX);
  return texture;
}

cv::Mat1f makeTileable(const cv::Mat1f& source, int margin) {
  if (margin < 1 || source.cols <= 2 * margin || source.rows <= 2 * margin) {
    throw InputError("makeTileable: the source must be larger than twice the margin (>= 1)");
  }
  const double mean = cv::mean(source)[0];
  // Fade weights: position i < margin continues the source's position `size + i` and turns into
  // position i; sin^2 + cos^2 = 1 keeps the variance.
  std::vector<float> keep(margin), fade(margin);
  for (int i = 0; i < margin; ++i) {
    const double w = (i + 0.5) / margin * (CV_PI / 2.0);
    keep[i] = static_cast<float>(std::sin(w));
    fade[i] = static_cast<float>(std::cos(w));
  }
  const auto blend = [&](float near, float far, int i) {
    return static_cast<float>(mean + keep[i] * (near - mean) + fade[i] * (far - mean));
  };
  // Columns first (keeping all rows), then rows of that result.
  const int width = source.cols - margin, height = source.rows - margin;
  cv::Mat1f columns(source.rows, width);
  for (int r = 0; r < source.rows; ++r) {
    const float* in = source[r];
    float* out = columns[r];
    for (int c = 0; c < width; ++c) out[c] = in[c];
    for (int c = 0; c < margin; ++c) out[c] = blend(in[c], in[width + c], c);
  }
  cv::Mat1f tile = columns.rowRange(0, height).clone();
  for (int r = 0; r < margin; ++r) {
    const float* near_row = columns[r];
    const float* far_row = columns[height + r];
    float* out = tile[r];
    for (int c = 0; c < width; ++c) out[c] = blend(near_row[c], far_row[c], r);
  }
  return tile;
}

cv::Mat1f tileableTexture(int size, std::uint32_t seed, TextureStyle style, double feature_px) {
  const int margin = std::max(4, size / 8);
  cv::Mat1f tile = makeTileable(proceduralTexture(cv::Size(size + margin, size + margin), seed, style, feature_px),
                                margin);
  cv::normalize(tile, tile, 0.0, 1.0, cv::NORM_MINMAX);
  return tile;
}

cv::Mat1f naturalTexture(int size, std::uint32_t seed, double feature_px) {
  if (size < 16) throw InputError("naturalTexture: size must be >= 16");
  if (!(feature_px >= 2.0)) throw InputError("naturalTexture: feature_px must be >= 2");
  cv::RNG rng(0x6A09E667F3BCC909ULL ^ seed);
  const int n = size;
  cv::Mat1f phase(n, n);
  rng.fill(phase, cv::RNG::UNIFORM, 0.0, 2.0 * CV_PI);
  // Natural images have an amplitude spectrum close to 1/f: the same contrast in every octave.
  // Below `corner` (structures wider than about 8 features, i.e. most of an image) it is flat so
  // that the largest waves do not turn every view into a brightness gradient.
  const double corner = n / (8.0 * feature_px);
  cv::Mat2f spectrum(n, n);
  for (int r = 0; r < n; ++r) {
    const double fr = r <= n / 2 ? r : r - n;
    const float* phase_row = phase[r];
    const float* mirror_row = phase[(n - r) % n];
    cv::Vec2f* out = spectrum[r];
    for (int c = 0; c < n; ++c) {
      const double fc = c <= n / 2 ? c : c - n;
      const double amplitude = r == 0 && c == 0 ? 0.0 : 1.0 / std::sqrt(fr * fr + fc * fc + corner * corner);
      // Odd in the frequency (phase(-f) = -phase(f)): a Hermitian spectrum, a real texture.
      const double p = static_cast<double>(phase_row[c]) - static_cast<double>(mirror_row[(n - c) % n]);
      out[c] = cv::Vec2f(static_cast<float>(amplitude * std::cos(p)), static_cast<float>(amplitude * std::sin(p)));
    }
  }
  phase.release();
  cv::Mat1f texture;
  // The inverse DFT is periodic: the texture tiles without a seam by construction.
  cv::dft(spectrum, texture, cv::DFT_INVERSE | cv::DFT_REAL_OUTPUT);
  spectrum.release();
  standardise(texture, 0.0, 1.0);
  addSoftPatches(texture, rng, feature_px);
  standardise(texture, 0.5, 0.15);
  clipToUnit(texture);
  return texture;
}

cv::Size brickSize(double brick_px) {
  // Bricks three times as long as high (a common brick's face with its mortar); an even height
  // so that half a brick, the rows' offset, is a whole number of texels.
  const int height = 2 * std::max(2, static_cast<int>(std::lround(brick_px / 6.0)));
  return {3 * height, height};
}

cv::Mat1f brickTexture(int size, std::uint32_t seed, double brick_px) {
  if (size < 16 || !(brick_px > 0.0)) throw InputError("brickTexture: size must be >= 16, brick_px > 0");
  const cv::Size brick = brickSize(brick_px);
  cv::RNG rng(0xBB67AE8584CAA73BULL ^ seed);
  const cv::Mat1f detail = cellDetail(brick, rng, 0.05);
  const double mortar_half_width = std::max(1.0, 0.08 * brick.height);
  cv::Mat1f cell(brick);
  for (int j = 0; j < brick.height; ++j) {
    // A little darker towards the bottom edge of each brick (shade under the row above).
    const double weathering = -0.05 * (j + 0.5) / brick.height;
    for (int i = 0; i < brick.width; ++i) {
      const double face = 0.62 + weathering + detail(j, i);
      const double mortar = 0.3;
      cell(j, i) = static_cast<float>(mortar + jointCoverage(i, j, brick, mortar_half_width) * (face - mortar));
    }
  }
  // Running bond: every other row shifted by half a brick. Rows of bricks repeat after two, so
  // two brick lengths (= six rows of bricks) make a square period.
  const int side = wholePeriods(size, 2 * brick.width);
  return repeatCell(cell, side, [&](int row) { return row % 2 == 0 ? 0 : brick.width / 2; });
}

int tileSide(double tile_px) { return 2 * std::max(6, static_cast<int>(std::lround(tile_px / 2.0))); }

cv::Mat1f tileTexture(int size, std::uint32_t seed, double tile_px) {
  if (size < 16 || !(tile_px > 0.0)) throw InputError("tileTexture: size must be >= 16, tile_px > 0");
  const int t = tileSide(tile_px);
  cv::RNG rng(0x3C6EF372FE94F82BULL ^ seed);
  const cv::Mat1f detail = cellDetail(cv::Size(t, t), rng, 0.04);
  const double grout_half_width = std::max(1.0, 0.04 * t);
  cv::Mat1f cell(t, t);
  for (int j = 0; j < t; ++j) {
    for (int i = 0; i < t; ++i) {
      const double x = (i + 0.5) / t, y = (j + 0.5) / t;
      // A dark disc in the middle and a small square off-centre: a motif without a symmetry
      // that a quarter turn would map onto itself.
      const double disc = smoothStep(0.5 + (0.22 - std::hypot(x - 0.5, y - 0.5)) * t);
      const double square = smoothStep(0.5 + (0.07 - std::max(std::fabs(x - 0.76), std::fabs(y - 0.24))) * t);
      const double face = 0.7 - 0.28 * disc - 0.18 * square + detail(j, i);
      const double grout = 0.28;
      cell(j, i) = static_cast<float>(grout + jointCoverage(i, j, cell.size(), grout_half_width) * (face - grout));
    }
  }
  return repeatCell(cell, wholePeriods(size, t), [](int) { return 0; });
}

cv::Mat1f withContrast(const cv::Mat1f& texture, double std) {
  cv::Mat1f out = texture.clone();
  standardise(out, 0.5, std);
  clipToUnit(out);
  return out;
}

}  // namespace sim
}  // namespace oefmt
