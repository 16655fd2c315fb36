// SPDX-License-Identifier: GPL-3.0-or-later
// The portable line sampler: OpenCV's 128-bit universal intrinsics (SSE on x86-64, NEON on
// ARM companion computers), four samples per step.
#include <opencv2/core/hal/intrin.hpp>

#include "bilinear_sample.h"

namespace oefmt {
namespace detail {

void sampleLinePortable(const LineSamples& line) {
  const float* src = line.source;
  const int cols = line.cols, rows = line.rows, stride = line.stride;
  int c = 0;
#if CV_SIMD128
  const cv::v_float32x4 lanes(0.0f, 1.0f, 2.0f, 3.0f);
  const cv::v_float32x4 dx = cv::v_setall_f32(line.dx), dy = cv::v_setall_f32(line.dy);
  const cv::v_float32x4 sx0 = cv::v_setall_f32(line.sx0), sy0 = cv::v_setall_f32(line.sy0);
  const cv::v_float32x4 offset = cv::v_setall_f32(line.offset);
  const cv::v_float32x4 weight = cv::v_setall_f32(line.row_weight);
  const cv::v_int32x4 zero = cv::v_setzero_s32();
  const cv::v_int32x4 max_x = cv::v_setall_s32(cols - 2), max_y = cv::v_setall_s32(rows - 2);
  const cv::v_int32x4 vstride = cv::v_setall_s32(stride);
  for (; c + 4 <= line.count; c += 4) {
    const cv::v_float32x4 t = line.positions ? cv::v_load(line.positions + c)
                                             : cv::v_setall_f32(static_cast<float>(c)) + lanes;
    const cv::v_float32x4 sx = sx0 + dx * t, sy = sy0 + dy * t;
    const cv::v_int32x4 ix = cv::v_floor(sx), iy = cv::v_floor(sy);
    // Four samples at a time where the whole 2 x 2 neighbourhood is inside the source.
    const cv::v_int32x4 inside = (ix >= zero) & (iy >= zero) & (ix <= max_x) & (iy <= max_y);
    if (!cv::v_check_all(inside)) {
      for (int k = c; k < c + 4; ++k) sampleLineAt(line, k);
      continue;
    }
    const cv::v_float32x4 fx = sx - cv::v_cvt_f32(ix), fy = sy - cv::v_cvt_f32(iy);
    const cv::v_int32x4 index = iy * vstride + ix;
    const cv::v_float32x4 p00 = cv::v_lut(src, index), p01 = cv::v_lut(src + 1, index);
    const cv::v_float32x4 p10 = cv::v_lut(src + stride, index);
    const cv::v_float32x4 p11 = cv::v_lut(src + stride + 1, index);
    const cv::v_float32x4 top = p00 + fx * (p01 - p00);
    const cv::v_float32x4 bottom = p10 + fx * (p11 - p10);
    const cv::v_float32x4 w = line.taper ? cv::v_load(line.taper + c) * weight : weight;
    cv::v_store(line.out + c, (top + fy * (bottom - top) - offset) * w);
  }
#endif
  for (; c < line.count; ++c) sampleLineAt(line, c);
}

}  // namespace detail
}  // namespace oefmt
