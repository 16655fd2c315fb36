// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/sim/texture.h"

#include <algorithm>
#include <cmath>
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

}  // namespace

cv::Mat1f proceduralTexture(cv::Size size, std::uint32_t seed, TextureStyle style,
                            double feature_px) {
  if (size.width <= 0 || size.height <= 0) throw InputError("proceduralTexture: empty size");
  if (!(feature_px >= 2.0)) throw InputError("proceduralTexture: feature_px must be >= 2");
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

}  // namespace sim
}  // namespace oefmt
