// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/registration/warp.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include "oefmt/error.h"
#include "simd_kernels.h"

namespace oefmt {
namespace {

// Output rows fetched ahead of the one being sampled: a row takes about a microsecond, longer
// than a fetch from memory.
constexpr int kPrefetchRowsAhead = 2;

// A hint to fetch the cache line at `address`. On x86-64 an asm statement: GCC's dead-code
// elimination removed a loop of __builtin_prefetch calls (nothing else in it has an effect).
inline void prefetchForRead(const float* address) {
#if defined(__x86_64__)
  asm volatile("prefetcht0 %0" : : "m"(*address));
#else
  __builtin_prefetch(address);
#endif
}

// Asks for the cache lines the samples of `line` will read (both bilinear rows), one touch per
// 64-byte line crossed. The hardware prefetcher does not follow a sampled line, which drifts
// across source rows: a source that is not already in cache (the older frame, last used when it
// was analysed) made the warp much slower than a cached one (BM_Stage_WarpUncachedOlder).
void prefetchLine(const detail::LineSamples& line) {
  constexpr float kFloatsPerCacheLine = 16.0f;
  // Samples per new cache line along the line; 1 when every sample may need one, and when the
  // transform is not finite (the bounds test then skips every position).
  const float spacing =
      1.0f / std::max(std::fabs(line.dx) / kFloatsPerCacheLine, std::fabs(line.dy));
  const int step =
      spacing >= 2.0f ? static_cast<int>(std::min(spacing, static_cast<float>(line.count))) : 1;
  for (int c = 0; c < line.count; c += step) {
    const float x = line.sx0 + line.dx * static_cast<float>(c);
    const float y = line.sy0 + line.dy * static_cast<float>(c);
    if (!(x >= 0.0f && y >= 0.0f && x < static_cast<float>(line.cols) &&
          y < static_cast<float>(line.rows - 1))) {
      continue;
    }
    const float* top =
        line.source + static_cast<std::ptrdiff_t>(y) * line.stride + static_cast<int>(x);
    prefetchForRead(top);
    prefetchForRead(top + line.stride);
  }
}

}  // namespace

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
  const double cx = imageCentre(cols), cy = imageCentre(rows);
  const float a00 = static_cast<float>(c), a01 = static_cast<float>(-s);
  const float a10 = static_cast<float>(s), a11 = static_cast<float>(c);
  const int stride = static_cast<int>(source.step1());
  const bool avx2 = detail::runsAvx2(kernel);
  auto lineOf = [&](int y) {
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
    return line;
  };
  for (int y = 0; y < std::min(kPrefetchRowsAhead, rows); ++y) prefetchLine(lineOf(y));
  for (int y = 0; y < rows; ++y) {
    if (y + kPrefetchRowsAhead < rows) prefetchLine(lineOf(y + kPrefetchRowsAhead));
    detail::sampleLine(lineOf(y), avx2);
  }
}

}  // namespace oefmt
