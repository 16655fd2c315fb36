// SPDX-License-Identifier: GPL-3.0-or-later
// Refines a pair's rotation, zoom and shift on the images themselves (Gauss-Newton on the
// intensities), after the spectral registration has found them to within a bin.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace oefmt {

/// A frame's image as the refinement reads it.
struct RefinementImage {
  cv::Mat1f smooth;  ///< the grey image, Gaussian-smoothed
  /// Variance of the grey image's white sensor noise, before the smoothing (0: none known).
  double noise_variance = 0.0;
  /// Non-zero where `smooth` is made of the camera's own pixels only (a levelled view fills in
  /// what the camera did not see: io/nadir_view.h); empty when all of it is. The refinement reads
  /// only pixels both frames saw.
  cv::Mat1b seen;

  bool empty() const { return smooth.empty(); }
};

/// Smooths `grey`, whose white sensor noise has the variance `noise_variance` (0: unknown).
/// `seen` (empty: all of it) is non-zero where `grey` holds what the camera saw; the result's
/// mask leaves out what the smoothing and the gradients mix into it from elsewhere. Throws
/// InputError for a mask of another size than `grey`.
RefinementImage makeRefinementImage(const cv::Mat1f& grey, double noise_variance = 0.0,
                                    const cv::Mat1b& seen = cv::Mat1b());

/// A similarity in the registration's convention (PairRegistration): the newer frame B shows the
/// older A turned by `rotation` (counter-clockwise on screen) and scaled by exp(log_zoom) about
/// the image centre, then shifted by `translation` [px].
struct ImageSimilarity {
  double rotation = 0.0;
  double log_zoom = 0.0;
  cv::Point2d translation;
  /// Area-preserving stretch S = [a b; b -a] applied after the rotation and zoom (B's content
  /// x_B - c = (I + S) s R (x_A - c) + d); zero for a similarity. A plane that is not
  /// perpendicular to the view stretches the images along the motion (see refineSimilarity).
  double stretch_a = 0.0;
  double stretch_b = 0.0;
};

struct SimilarityRefinement {
  bool converged = false;   ///< the steps shrank below the tolerance within the iterations
  ImageSimilarity similarity;    ///< the refined motion (the start when nothing was refined)
  double residual_start = 0.0;  ///< robust sigma of the intensity residuals at the start
  double residual_end = 0.0;    ///< ... at the refined motion (negative: too few pixels)
  int pixels = 0;               ///< pixels of the sparse grid inside both frames at the end
  /// Mean of Tukey's biweight loss (0..1) of the residuals at the start's robust sigma, at the
  /// start and at the refined motion (negative: too few pixels): the fit improved when it fell.
  double loss_start = -1.0;
  double loss_end = -1.0;
  /// The loss's change from the start to the refined motion over the pixels both see at both
  /// (paired), and the standard error of that mean change (0 when too few pixels took part).
  double loss_change = 0.0;
  double loss_change_sigma = 0.0;
  /// Standard deviation of the rotation [rad] the last step solved for, from its normal
  /// equations and the residuals' robust sigma (0: no step was solved). It describes the pixels'
  /// noise, not a model that does not fit (several depth layers): calibrate before use.
  double rotation_sigma = 0.0;
  /// The same of ln(zoom).
  double log_zoom_sigma = 0.0;
  /// Covariance of (rotation, stretch_a, stretch_b) from the same normal equations, for a reading
  /// that combines them (zero when no step was solved or the stretch was not fitted).
  cv::Matx33d rotation_stretch_covariance = cv::Matx33d::zeros();
  /// Blocks of the image (of 64) left out because another depth layer's shift fits them better.
  int dropped_blocks = 0;
  /// Cells of the kept blocks (3 x 3 pixels of the sparse grid each) left out because another
  /// shift along the motion fits them better.
  int dropped_cells = 0;
  /// The last step's change of the rotation [rad]: how far the iteration still moved when it
  /// stopped (one that has found its minimum moves it by a tiny fraction of its first step).
  double last_rotation_step = 0.0;
};

/// Gauss-Newton on B(x) = gain * A(warp(x)) + bias over the pixels both frames see (inside both,
/// and seen by both cameras: RefinementImage::seen), weighted by
/// `taper` (the apodization, on both axes) and by Tukey's biweight at the residuals' robust sigma
/// (measured before each step, at the residuals' lower quartile), so that a layer moving
/// otherwise (parallax) or new content counts for little. Every `stride`-th pixel of every
/// `stride`-th row takes part in the `iterations` steps. The bias starts at the frames' mean
/// difference over those pixels (an exposure change), and where the frames' noise variances are
/// known the gradients' noise is taken out of the normal equations, which it would otherwise
/// inflate, shortening every step. `other_layers` are the shifts [px] of the pair's other depth
/// layers (the translation energy vector's other peaks): before the steps, every block of the
/// image (8 x 8) that one of them explains better than the start's shift, by three standard
/// errors of the mean difference of the squared residuals over the block's pixels, is left out,
/// so that the steps measure the followed layer's motion also where the texture is too weak
/// against the noise for the biweight to tell another layer's pixels from noisy ones. The same
/// test then runs on each cell of 3 x 3 grid pixels of the kept blocks, on 25 samples around its
/// centre, against the other layers' shifts and three evenly spaced between the start's and each
/// of them: where layers meet a block holds several surfaces, and walls or slopes, whose shift
/// varies with their height, fit no one layer's shift better than the followed one's.
SimilarityRefinement refineSimilarity(const RefinementImage& older, const RefinementImage& newer,
                                      const ImageSimilarity& start, const std::vector<float>& taper,
                                      int iterations, int stride, bool fit_stretch = false,
                                      const std::vector<cv::Point2d>& other_layers = {});

}  // namespace oefmt
