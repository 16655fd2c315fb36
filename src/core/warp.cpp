// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/warp.h"

#include <cmath>

#include "oefmt/error.h"
#include "simd_kernels.h"

namespace oefmt {

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
  const bool avx2 = detail::runsAvx2(kernel);
  for (int y = 0; y < rows; ++y) {
    const double dy = y - cy;
    // Source point of output (0, y); column x adds x * (a00, a10). Window: taper(y) * taper(x).
    detail::LineSamples line{};
    line.source = source.ptr<float>();
    line.stride = stride;
    line.cols = cols;
    line.rows = rows;
    line.sx0 = static_cast<float>(cx - a00 * cx + a01 * dy);
    line.sy0 = static_cast<float>(cy - a10 * cx + a11 * dy);
    line.dx = a00;
    line.dy = a10;
    line.row_weight = window.taper()[y];
    line.taper = window.taper().data();
    line.offset = offset;
    line.count = cols;
    line.out = out[y];
    detail::sampleLine(line, avx2);
  }
}

}  // namespace oefmt
