// SPDX-License-Identifier: GPL-3.0-or-later
// Precomputed bilinear resampling (log-polar and polar unwraps): one table lookup and four
// multiply-adds per output pixel, no per-pixel trigonometry, zero outside the source.
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/simd_kernel.h"

namespace oefmt {

class BilinearRemapTable {
 public:
  /// Maps output pixel (row, col) of an `output`-sized image to the source point
  /// sample(row, col) = (x, y) of a continuous `source`-sized image (at least 2 x 2).
  BilinearRemapTable(cv::Size output, cv::Size source,
                     const std::function<cv::Point2d(int row, int col)>& sample);
  BilinearRemapTable() = default;

  cv::Size outputSize() const { return output_; }
  cv::Size sourceSize() const { return source_; }

  /// out (output size) = source resampled.
  void apply(const cv::Mat1f& source, cv::Mat1f& out,
             SimdKernel kernel = SimdKernel::kAuto) const;
  /// out (count x output width) = output rows first_row .. first_row + count - 1, taken
  /// cyclically (row indices wrap around the output height).
  void applyRows(const cv::Mat1f& source, int first_row, int count, cv::Mat1f& out,
                 SimdKernel kernel = SimdKernel::kAuto) const;

 private:
  void applyRow(const float* source, int row, float* out, bool avx2) const;

  cv::Size output_;
  cv::Size source_;
  // One entry per output pixel, structure of arrays for vector loads: the index of the
  // top-left of a 2 x 2 source block fully inside the source, and the weights of its
  // top-left, top-right, bottom-left and bottom-right pixels (0 for those outside the source).
  std::vector<std::int32_t> offset_;
  std::vector<float> weight_[4];
};

}  // namespace oefmt
