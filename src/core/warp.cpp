// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/warp.h"

#include <cmath>

#include <opencv2/core/hal/intrin.hpp>

#include "oefmt/error.h"
#include "bilinear_sample.h"
#include "simd_kernels.h"

namespace oefmt {
using detail::sampleBilinear;

void warpSimilarityWindowed(const cv::Mat1f& source, double rotation, double zoom,
                            const SeparableWindow& window, cv::Mat1f& out, float offset,
                            SimdKernel kernel) {
  if (source.empty() || source.rows != window.size() || source.cols != window.size() ||
      !(zoom > 0.0) || !source.isContinuous()) {
    throw InputError("warpSimilarityWindowed: bad source, window or zoom");
  }
  const int rows = source.rows, cols = source.cols;
  out.create(rows, cols);
  // Inverse map (output -> source). Screen counter-clockwise with y down is the matrix
  // [cos sin; -sin cos] (OpenCV's getRotationMatrix2D); its inverse divided by zoom:
  const double c = std::cos(rotation) / zoom, s = std::sin(rotation) / zoom;
  const double cx = cols / 2, cy = rows / 2;
  const float a00 = static_cast<float>(c), a01 = static_cast<float>(-s);
  const float a10 = static_cast<float>(s), a11 = static_cast<float>(c);
  const int stride = static_cast<int>(source.step1());
  const float* src = source.ptr<float>();
  const bool avx2 = kernel == SimdKernel::kAuto && cpuRunsAvx2Kernels();
  for (int y = 0; y < rows; ++y) {
    const double dy = y - cy;
    // Source point of output (0, y); column x adds x * (a00, a10).
    const float sx0 = static_cast<float>(cx - a00 * cx + a01 * dy);
    const float sy0 = static_cast<float>(cy - a10 * cx + a11 * dy);
    // Window: taper(y) * taper(x); the row's factor is folded into the taper per column.
    const float row_weight = window.taper()[y];
    const float* taper = window.taper().data();
    float* o = out[y];
    if (avx2) {
      detail::warpRowAvx2({src, stride, cols, rows, sx0, sy0, a00, a10, row_weight, taper, offset, o});
      continue;
    }
    int x = 0;
#if CV_SIMD128
    // Four pixels at a time where the whole 2 x 2 neighbourhood is inside the source.
    const cv::v_float32x4 lanes(0.0f, 1.0f, 2.0f, 3.0f);
    const cv::v_float32x4 va00 = cv::v_setall_f32(a00), va10 = cv::v_setall_f32(a10);
    const cv::v_int32x4 zero = cv::v_setzero_s32();
    const cv::v_int32x4 max_x = cv::v_setall_s32(cols - 2), max_y = cv::v_setall_s32(rows - 2);
    const cv::v_int32x4 vstride = cv::v_setall_s32(stride);
    for (; x + 4 <= cols; x += 4) {
      const cv::v_float32x4 vx = cv::v_setall_f32(static_cast<float>(x)) + lanes;
      const cv::v_float32x4 sx = cv::v_setall_f32(sx0) + va00 * vx;
      const cv::v_float32x4 sy = cv::v_setall_f32(sy0) + va10 * vx;
      const cv::v_int32x4 ix = cv::v_floor(sx), iy = cv::v_floor(sy);
      const cv::v_int32x4 inside = (ix >= zero) & (iy >= zero) & (ix <= max_x) & (iy <= max_y);
      if (!cv::v_check_all(inside)) {
        float sxs[4], sys[4];
        cv::v_store(sxs, sx);
        cv::v_store(sys, sy);
        for (int k = 0; k < 4; ++k) {
          o[x + k] = row_weight * taper[x + k] * sampleBilinear(src, stride, cols, rows, sxs[k], sys[k], offset);
        }
        continue;
      }
      const cv::v_float32x4 fx = sx - cv::v_cvt_f32(ix), fy = sy - cv::v_cvt_f32(iy);
      const cv::v_int32x4 index = iy * vstride + ix;
      const cv::v_float32x4 p00 = cv::v_lut(src, index), p01 = cv::v_lut(src + 1, index);
      const cv::v_float32x4 p10 = cv::v_lut(src + stride, index), p11 = cv::v_lut(src + stride + 1, index);
      const cv::v_float32x4 top = p00 + fx * (p01 - p00);
      const cv::v_float32x4 bottom = p10 + fx * (p11 - p10);
      cv::v_store(o + x, (top + fy * (bottom - top) - cv::v_setall_f32(offset)) *
                             cv::v_load(taper + x) * cv::v_setall_f32(row_weight));
    }
#endif
    for (; x < cols; ++x) {
      o[x] = row_weight * taper[x] * sampleBilinear(src, stride, cols, rows, sx0 + a00 * x, sy0 + a10 * x, offset);
    }
  }
}

}  // namespace oefmt
