// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/remap_table.h"

#include <algorithm>
#include <cmath>

#include "oefmt/error.h"

namespace oefmt {

BilinearRemapTable::BilinearRemapTable(cv::Size output, cv::Size source,
                                       const std::function<cv::Point2d(int, int)>& sample)
    : output_(output), source_(source), taps_(static_cast<size_t>(output.area())) {
  if (source.width < 2 || source.height < 2) throw InputError("remap table: source under 2 x 2");
  for (int r = 0; r < output.height; ++r) {
    for (int c = 0; c < output.width; ++c) {
      const cv::Point2d p = sample(r, c);
      Tap& tap = taps_[static_cast<size_t>(r) * output.width + c];
      std::fill(std::begin(tap.weight), std::end(tap.weight), 0.0f);
      const double x0 = std::floor(p.x), y0 = std::floor(p.y);
      const double fx = p.x - x0, fy = p.y - y0;
      // Clamp the block inside the source and give outside neighbours no weight, so that the
      // inner loop needs no bounds test.
      const int base_x = static_cast<int>(std::clamp(x0, 0.0, source.width - 2.0));
      const int base_y = static_cast<int>(std::clamp(y0, 0.0, source.height - 2.0));
      tap.offset = base_y * source.width + base_x;
      const double weights[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
      for (int k = 0; k < 4; ++k) {
        const double x = x0 + (k & 1), y = y0 + (k >> 1);
        if (x < 0 || y < 0 || x >= source.width || y >= source.height) continue;
        const int slot = static_cast<int>(x - base_x) + 2 * static_cast<int>(y - base_y);
        tap.weight[slot] += static_cast<float>(weights[k]);
      }
    }
  }
}

void BilinearRemapTable::applyRow(const float* source, int row, float* out) const {
  const Tap* tap = &taps_[static_cast<size_t>(row) * output_.width];
  const int stride = source_.width;
  for (int c = 0; c < output_.width; ++c) {
    const float* p = source + tap[c].offset;
    const float* w = tap[c].weight;
    out[c] = w[0] * p[0] + w[1] * p[1] + w[2] * p[stride] + w[3] * p[stride + 1];
  }
}

void BilinearRemapTable::apply(const cv::Mat1f& source, cv::Mat1f& out) const {
  applyRows(source, 0, output_.height, out);
}

void BilinearRemapTable::applyRows(const cv::Mat1f& source, int first_row, int count,
                                   cv::Mat1f& out) const {
  if (source.size() != source_ || !source.isContinuous()) {
    throw InputError("remap table: source must be a continuous " + std::to_string(source_.width) +
                     "x" + std::to_string(source_.height) + " image");
  }
  out.create(count, output_.width);
  for (int i = 0; i < count; ++i) {
    const int row = ((first_row + i) % output_.height + output_.height) % output_.height;
    applyRow(source.ptr<float>(), row, out[i]);
  }
}

}  // namespace oefmt
