// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/registration/image_prep.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"
#include "simd_kernels.h"

namespace oefmt {
namespace {

std::string describe(const cv::Mat& image) {
  return cv::typeToString(image.type()) + " " + std::to_string(image.cols) + "x" +
         std::to_string(image.rows);
}

// Replaces NaN/inf by the mean of the finite pixels; returns how many were replaced.
int replaceNonFinite(cv::Mat1f& grey) {
  int invalid = 0;
  double sum = 0.0;
  for (int r = 0; r < grey.rows; ++r) {
    const float* row = grey[r];
    for (int c = 0; c < grey.cols; ++c) {
      if (std::isfinite(row[c])) {
        sum += row[c];
      } else {
        ++invalid;
      }
    }
  }
  if (invalid == 0) return 0;
  const long valid = static_cast<long>(grey.total()) - invalid;
  const float fill = valid > 0 ? static_cast<float>(sum / static_cast<double>(valid)) : 0.0f;
  for (int r = 0; r < grey.rows; ++r) {
    float* row = grey[r];
    for (int c = 0; c < grey.cols; ++c) {
      if (!std::isfinite(row[c])) row[c] = fill;
    }
  }
  return invalid;
}

struct PixelMoments {
  double mean = 0.0, mean_square = 0.0, largest_magnitude = 0.0;
};

// Mean, mean square and largest |pixel| in one pass of vectorised row statistics (float per row,
// double over rows; cv::sum, cv::norm, cv::mean and cv::minMaxLoc take four passes over the
// frame). Squares of huge float pixels overflow a float row sum: double sums then.
PixelMoments pixelMoments(const cv::Mat1f& grey) {
  const detail::SurfaceTotals totals =
      detail::surfaceTotals(grey[0], static_cast<int>(grey.step1()), grey.rows, grey.cols,
                            detail::runsAvx2(SimdKernel::kAuto));
  double sum = totals.sum, square_sum = totals.square_sum;
  if (!std::isfinite(square_sum)) {
    sum = square_sum = 0.0;
    for (int r = 0; r < grey.rows; ++r) {
      const float* row = grey[r];
      double row_sum = 0.0, row_square_sum = 0.0;
#pragma omp simd reduction(+ : row_sum, row_square_sum)
      for (int c = 0; c < grey.cols; ++c) {
        const double value = row[c];
        row_sum += value;
        row_square_sum += value * value;
      }
      sum += row_sum;
      square_sum += row_square_sum;
    }
  }
  const double count = static_cast<double>(grey.total());
  return {sum / count, square_sum / count,
          std::max(static_cast<double>(totals.max), -static_cast<double>(totals.min))};
}

}  // namespace

cv::Mat1f toGreyFloat(const cv::Mat& image, ChannelOrder order) {
  if (image.empty()) throw InputError("image is empty");
  const int channels = image.channels();
  if (channels != 1 && channels != 3 && channels != 4) {
    throw InputError("unsupported image (" + describe(image) + "): expected 1, 3 or 4 channels");
  }
  double scale = 1.0;
  switch (image.depth()) {
    case CV_8U: scale = 1.0 / 255.0; break;
    case CV_16U: scale = 1.0 / 65535.0; break;
    case CV_32F:
    case CV_64F: break;
    default:
      throw InputError("unsupported image (" + describe(image) +
                       "): expected 8-bit, 16-bit unsigned or floating-point pixels");
  }
  cv::Mat source = image;
  if (image.depth() == CV_64F) image.convertTo(source, CV_MAKETYPE(CV_32F, channels));
  cv::Mat grey = source;
  if (channels == 3) {
    cv::cvtColor(source, grey, order == ChannelOrder::kBgr ? cv::COLOR_BGR2GRAY : cv::COLOR_RGB2GRAY);
  } else if (channels == 4) {
    cv::cvtColor(source, grey, order == ChannelOrder::kBgr ? cv::COLOR_BGRA2GRAY : cv::COLOR_RGBA2GRAY);
  }
  cv::Mat1f out;
  grey.convertTo(out, CV_32F, scale);
  return out;
}

void requireRegistrableSize(const cv::Mat& image) {
  if (image.empty()) throw InputError("image is empty");
  if (std::min(image.cols, image.rows) < kMinImageSide) {
    throw InputError("image of " + std::to_string(image.cols) + "x" + std::to_string(image.rows) +
                     " pixels: its centre square must be at least " + std::to_string(kMinImageSide) +
                     " px (too little detail to register)");
  }
}

std::string upscalingWarning(cv::Size image_size, int size) {
  const int side = std::min(image_size.width, image_size.height);
  if (side >= size) return std::string();
  return "the images (" + std::to_string(image_size.width) + "x" + std::to_string(image_size.height) +
         ") are upscaled to registration.size " + std::to_string(size) +
         ", which registers worse than working at their own size: set registration.size to at most " +
         std::to_string(side / 2 * 2);
}

PreparedImage prepareImage(const cv::Mat& image, int size, ChannelOrder order) {
  if (size < 64 || size % 2 != 0) {
    throw InputError("working size must be even and >= 64, got " + std::to_string(size));
  }
  requireRegistrableSize(image);
  const int side = std::min(image.cols, image.rows);
  // Crop first (a view), then convert: a 4056 x 3040 frame converts only its centre square.
  const cv::Rect square((image.cols - side) / 2, (image.rows - side) / 2, side, side);
  const bool already_square = image.cols == image.rows;
  cv::Mat1f cropped = toGreyFloat(already_square ? image : image(square), order);
  if (!cropped.isContinuous()) cropped = cropped.clone();
  PreparedImage prepared;
  // Only float inputs can hold NaN/inf; a finite sum (vectorised) proves there are none.
  const int depth = image.depth();
  if ((depth == CV_32F || depth == CV_64F) && !std::isfinite(cv::sum(cropped)[0])) {
    prepared.invalid_pixels = replaceNonFinite(cropped);
  }
  if (side == size) {
    prepared.grey = cropped;
  } else {
    cv::resize(cropped, prepared.grey, cv::Size(size, size), 0.0, 0.0,
               side > size ? cv::INTER_AREA : cv::INTER_LINEAR);
    // Interpolating float pixels near +-FLT_MAX (sentinel values) can overflow to inf.
    if ((depth == CV_32F || depth == CV_64F) && !std::isfinite(cv::sum(prepared.grey)[0])) {
      replaceNonFinite(prepared.grey);
    }
  }
  const PixelMoments moments = pixelMoments(prepared.grey);
  prepared.texture = std::sqrt(std::max(moments.mean_square - moments.mean * moments.mean, 0.0));
  prepared.mean = moments.mean;
  prepared.largest_magnitude = moments.largest_magnitude;
  return prepared;
}

}  // namespace oefmt
