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
  /// The reading is the fit of the shifts across the pair's motion only (BlockFit).
  bool across_motion = false;
};

/// Which components of the blocks' shifts the fit reads.
enum class BlockFit {
  kBoth,          ///< both components: all the information, if the scene is one rigid plane
  kAcrossMotion,  ///< the component across the pair's shift only: blind to parallax
  kBest,          ///< both fits; the one whose rotation sigma is smaller
};

/// Reads a pair's rotation and zoom from the shifts of its image blocks: a second witness beside
/// the intensity refinement (similarity_refinement.h), which weighs every pixel at once and can
/// slide along the valley of a striped texture or towards several layers' compromise. The newer
/// frame is sampled where a similarity near the pair's motion puts each of the older frame's
/// blocks (about N/8 pixels square, side by side within an 8-pixel margin: 49 at most, those
/// inside both frames), each block's remaining shift is read by phase correlation (a Hann window;
/// the peak's position to a fraction of a pixel from a Gaussian through its neighbours), and the
/// shifts of the blocks that follow the pair's motion (within kFollowRadius pixels, with a clear
/// peak) are fitted by a shift, a turn and a zoom about the image centre, with Tukey's biweight
/// at their robust scatter. A block where another depth layer or a periodic texture's alias
/// moves otherwise leaves the fit.
///
/// Depth moves a block along the camera's translation only: a level camera's view of a nearer
/// point moves further, but in the same direction, and a yaw turns every depth alike. Layers
/// whose shifts differ by less than the follow radius (a roof a little higher, an inclined roof,
/// a wall) stay in a fit of both components and, where they lie to one side, turn it by
/// milliradians. The components across the motion hold none of that: their fit reads the turn
/// from how they change along the motion, with half the readings. kBest makes both fits, each
/// sigma from its scatter over its own degrees of freedom, and reports the one whose rotation
/// sigma is smaller: across the motion where layers pull, both components on one rigid plane.
/// The across fit needs a shift of at least kMinAcrossShift pixels to know its direction.
/// Holds scratch buffers and an FFT plan: one reader per thread.
class BlockMotionReader {
 public:
  /// Frames under this many pixels give blocks too small to correlate.
  static constexpr int kMinImageSize = 64;

  /// Blocks of image_size / 8 pixels, rounded down to even. Throws InputError for frames under
  /// kMinImageSize pixels.
  BlockMotionReader(int image_size, FftPlanning planning);

  /// `older` and `newer` are N x N grey frames; `motion` the pair's similarity to within a pixel
  /// or two at the image's edge (the refinement's or the surface's). Nothing valid when fewer
  /// than kMinBlocks blocks follow it, or the fit asked for has no more readings than unknowns.
  BlockMotion read(const cv::Mat1f& older, const cv::Mat1f& newer, const ImageSimilarity& motion,
                   BlockFit fit = BlockFit::kBest);

  int blockSize() const { return block_; }

 private:
  struct BlockShift {
    cv::Point2d position;  // block centre, relative to the image centre [px]
    cv::Point2d shift;     // remaining shift of the newer frame's block [px]
  };
  // The robust fit of the blocks' shifts (both components, or those across `across`, a unit
  // vector), on top of `motion`; `tried`: the blocks inside both frames.
  BlockMotion fitShifts(const ImageSimilarity& motion, const cv::Point2d* across, int tried) const;
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
