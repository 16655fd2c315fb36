// SPDX-License-Identifier: GPL-3.0-or-later
// A registered pair's rotation and zoom read from the shifts of its image blocks.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/registration/fft.h"
#include "oefmt/registration/similarity_refinement.h"

namespace oefmt {

/// The rotation and zoom that the blocks following a pair's shift agree on.
struct BlockMotion {
  bool valid = false;            ///< enough blocks followed the shift to read a rotation and zoom
  double rotation = 0.0;         ///< [rad], PairRegistration's convention
  double log_zoom = 0.0;         ///< ln s
  double rotation_sigma = 0.0;   ///< [rad], from the scatter of the blocks' shifts about the fit
  double log_zoom_sigma = 0.0;   ///< [ln s], likewise
  /// Blocks that followed the pair's shift (those the fit kept, when valid).
  int blocks = 0;
  int tried = 0;                 ///< blocks inside both frames
};

/// Reads a pair's rotation and zoom from the shifts of its image blocks: a second witness beside
/// the intensity refinement (similarity_refinement.h), which weighs every pixel at once and can
/// slide along the valley of a striped texture or towards several layers' compromise. The newer
/// frame is sampled where a similarity near the pair's motion puts each of the older frame's
/// blocks (about N/8 pixels square, side by side within an 8-pixel margin: 49 at most, those
/// inside both frames), each block's remaining shift is read by phase correlation (a Hann window; the
/// peak's position to a fraction of a pixel from a Gaussian through its neighbours), and the
/// shifts of the blocks that follow the pair's motion (within kFollowRadius pixels, with a clear
/// peak) are fitted by a shift, a turn and a zoom about the image centre, with Tukey's biweight
/// at their robust scatter. A block where another depth layer or a periodic texture's alias
/// moves otherwise leaves the fit; a rigid layer's blocks agree on the turn to a small fraction
/// of a pixel at the image's edge. Content whose shift changes gently across a block (a slope, a
/// wall seen at a grazing angle) stays in and pulls the fit, as it pulls the refinement: the
/// registration asks the blocks only where the refinement did not settle, and weighs the two by
/// their sigmas. Holds scratch buffers and an FFT plan: one reader per thread.
class BlockMotionReader {
 public:
  /// Blocks of image_size / 8 pixels, rounded down to even. Throws InputError for frames under
  /// 64 pixels.
  BlockMotionReader(int image_size, FftPlanning planning);

  /// `older` and `newer` are N x N grey frames; `motion` the pair's similarity to within a pixel
  /// or two at the image's edge (the refinement's or the surface's). Nothing valid when fewer
  /// than kMinBlocks blocks follow it.
  BlockMotion read(const cv::Mat1f& older, const cv::Mat1f& newer, const ImageSimilarity& motion);

  int blockSize() const { return block_; }

 private:
  struct BlockShift {
    cv::Point2d position;  // block centre, relative to the image centre [px]
    cv::Point2d shift;     // remaining shift of the newer frame's block [px]
  };
  // The remaining shift of one block and whether its correlation peak stands clear.
  // `older_to_newer`: where the pair's similarity puts an older pixel in the newer frame.
  bool blockShift(const cv::Mat1f& older, const cv::Mat1f& newer, const cv::Matx23d& older_to_newer,
                  const cv::Rect& block, cv::Point2d& shift);

  int size_;
  int block_;
  Fft2d fft_;
  cv::Mat1f window_;
  cv::Mat1f surface_;  // a view of newer_spectrum_ (in-place FFTs)
  cv::Mat2f older_spectrum_, newer_spectrum_;
  std::vector<BlockShift> shifts_;
};

}  // namespace oefmt
