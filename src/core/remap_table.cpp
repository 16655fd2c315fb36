// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/remap_table.h"

#include <algorithm>
#include <cmath>

#include <opencv2/core/hal/intrin.hpp>

#include "oefmt/error.h"
#include "simd_kernels.h"

namespace oefmt {

BilinearRemapTable::BilinearRemapTable(cv::Size output, cv::Size source,
                                       const std::function<cv::Point2d(int, int)>& sample)
    : output_(output), source_(source), offset_(static_cast<size_t>(output.area())) {
  for (auto& w : weight_) w.assign(offset_.size(), 0.0f);
  if (source.width < 2 || source.height < 2) throw InputError("remap table: source under 2 x 2");
  for (int r = 0; r < output.height; ++r) {
    for (int c = 0; c < output.width; ++c) {
      const cv::Point2d p = sample(r, c);
      const size_t i = static_cast<size_t>(r) * output.width + c;
      const double x0 = std::floor(p.x), y0 = std::floor(p.y);
      const double fx = p.x - x0, fy = p.y - y0;
      // Clamp the block inside the source and give outside neighbours no weight, so that the
      // inner loop needs no bounds test.
      const int base_x = static_cast<int>(std::clamp(x0, 0.0, source.width - 2.0));
      const int base_y = static_cast<int>(std::clamp(y0, 0.0, source.height - 2.0));
      offset_[i] = base_y * source.width + base_x;
      const double weights[4] = {(1 - fx) * (1 - fy), fx * (1 - fy), (1 - fx) * fy, fx * fy};
      for (int k = 0; k < 4; ++k) {
        const double x = x0 + (k & 1), y = y0 + (k >> 1);
        if (x < 0 || y < 0 || x >= source.width || y >= source.height) continue;
        const int slot = static_cast<int>(x - base_x) + 2 * static_cast<int>(y - base_y);
        weight_[slot][i] += static_cast<float>(weights[k]);
      }
    }
  }
}

void BilinearRemapTable::applyRow(const float* source, int row, float* out, bool avx2) const {
  const size_t first = static_cast<size_t>(row) * output_.width;
  const std::int32_t* offset = offset_.data() + first;
  const float* w0 = weight_[0].data() + first;
  const float* w1 = weight_[1].data() + first;
  const float* w2 = weight_[2].data() + first;
  const float* w3 = weight_[3].data() + first;
  const int stride = source_.width;
  if (avx2) {
    detail::remapRowAvx2({source, stride, offset, {w0, w1, w2, w3}, output_.width, out});
    return;
  }
  int c = 0;
#if CV_SIMD128
  for (; c + 4 <= output_.width; c += 4) {
    const cv::v_int32x4 index = cv::v_load(offset + c);
    const cv::v_float32x4 top = cv::v_load(w0 + c) * cv::v_lut(source, index) +
                                cv::v_load(w1 + c) * cv::v_lut(source + 1, index);
    const cv::v_float32x4 bottom = cv::v_load(w2 + c) * cv::v_lut(source + stride, index) +
                                   cv::v_load(w3 + c) * cv::v_lut(source + stride + 1, index);
    cv::v_store(out + c, top + bottom);
  }
#endif
  for (; c < output_.width; ++c) {
    const float* p = source + offset[c];
    out[c] = w0[c] * p[0] + w1[c] * p[1] + w2[c] * p[stride] + w3[c] * p[stride + 1];
  }
}

void BilinearRemapTable::apply(const cv::Mat1f& source, cv::Mat1f& out, SimdKernel kernel) const {
  applyRows(source, 0, output_.height, out, kernel);
}

void BilinearRemapTable::applyRows(const cv::Mat1f& source, int first_row, int count,
                                   cv::Mat1f& out, SimdKernel kernel) const {
  if (source.size() != source_ || !source.isContinuous()) {
    throw InputError("remap table: source must be a continuous " + std::to_string(source_.width) +
                     "x" + std::to_string(source_.height) + " image");
  }
  out.create(count, output_.width);
  const bool avx2 = kernel == SimdKernel::kAuto && cpuRunsAvx2Kernels();
  for (int i = 0; i < count; ++i) {
    const int row = ((first_row + i) % output_.height + output_.height) % output_.height;
    applyRow(source.ptr<float>(), row, out[i], avx2);
  }
}

}  // namespace oefmt
