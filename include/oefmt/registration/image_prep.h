// SPDX-License-Identifier: GPL-3.0-or-later
// Image preparation: any camera image -> grey float, centre-cropped square of N x N pixels.
#pragma once

#include <limits>
#include <string>

#include <opencv2/core.hpp>

namespace oefmt {

/// Order of the colour channels of a 3- or 4-channel image.
enum class ChannelOrder { kBgr, kRgb };

/// Pinhole intrinsics in pixels of the image they belong to.
struct Intrinsics {
  double fx = 0.0;
  double fy = 0.0;
  double cx = 0.0;
  double cy = 0.0;
  int width = 0;
  int height = 0;
  bool valid() const { return fx > 0.0 && fy > 0.0 && width > 0 && height > 0; }
};

/// A frame ready for spectral analysis, with the figures the registration needs to judge it.
struct PreparedImage {
  cv::Mat1f grey;          ///< size x size, intensities in [0, 1] for integer inputs
  int invalid_pixels = 0;  ///< NaN/inf pixels of the input, replaced by the mean of the valid ones
  double texture = 0.0;    ///< standard deviation of grey (0 for constant or black frames)
  /// Mean and largest |value| of grey, taken by prepareImage in the pass that gives the texture
  /// (the spectra need both); NaN when unknown (an image prepared elsewhere): computed then.
  double mean = std::numeric_limits<double>::quiet_NaN();
  double largest_magnitude = std::numeric_limits<double>::quiet_NaN();
  /// Non-zero where grey is the camera's own pixel, zero where it was filled in (a levelled
  /// view's part the camera did not see, and the fade into it: io/nadir_view.h); empty when all
  /// of it is the camera's. The spectra take the fill; the zoom refinement reads only what both
  /// frames saw.
  cv::Mat1b seen;
};

/// Converts any 1/3/4-channel 8-bit, 16-bit, 32-bit or 64-bit float image to single-channel float.
/// Integer types are scaled to [0, 1]; float types are kept as they are.
/// Throws InputError for an empty image or an unsupported pixel type (the message names it).
cv::Mat1f toGreyFloat(const cv::Mat& image, ChannelOrder order = ChannelOrder::kBgr);

/// Smallest centre square (min(W, H)) an input image may have: smaller frames hold too little
/// detail to register and are refused rather than blown up to the working size.
constexpr int kMinImageSide = 64;

/// Throws InputError, with the size, for an empty image or one whose square is under
/// kMinImageSide (prepareImage's own check, for callers that must refuse such a frame first).
void requireRegistrableSize(const cv::Mat& image);

/// The warning to give when frames of `image_size` are upscaled to the working size `size`
/// (which registers far worse than working at their own size: upscaling adds no detail, only
/// interpolated texture), naming the size to set; empty when they are not.
std::string upscalingWarning(cv::Size image_size, int size);

/// Centre-crops the image to a min(W, H) square, converts it to grey float (toGreyFloat) and
/// resizes it to size x size (area interpolation when shrinking, bilinear when growing).
/// Non-finite pixels are replaced and counted.
/// Throws InputError when size is odd or < 64, the image is empty, its square is under
/// kMinImageSide or its pixel type is unsupported.
PreparedImage prepareImage(const cv::Mat& image, int size,
                           ChannelOrder order = ChannelOrder::kBgr);

}  // namespace oefmt
