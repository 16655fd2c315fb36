// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/registration/similarity_refinement.h"

#include <algorithm>
#include <cmath>
#include <cstddef>

#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"
#include "oefmt/registration/robust_statistics.h"
#include "oefmt/registration/warp.h"

namespace oefmt {
namespace {

// Smoothing before the gradients [px]: a lens-sharp frame has gradients only a pixel wide, which
// a warp off by a pixel at the image's edge no longer overlaps.
constexpr double kSmoothingSigma = 1.0;
constexpr int kSmoothingTaps = 5;

// Tukey's biweight threshold in robust sigmas (95 % efficiency on Gaussian residuals): a pixel
// of another depth layer, which moves by pixels more than the followed one, counts for nothing.
constexpr double kTukey = 4.685;

// Steps below these count as converged [rad, ln, px].
constexpr double kAngleTolerance = 1e-5;
constexpr double kShiftTolerance = 1e-3;

// Parameters: rotation, log zoom, shift x, shift y, gain, bias, and optionally the stretch a, b.
constexpr int kParameters = 8;
constexpr int kSimilarityParameters = 6;
using Normal = cv::Matx<double, kParameters, kParameters>;
using Vector = cv::Vec<double, kParameters>;

// The intensity residual of one pixel of the newer frame against the warped older one, and the
// symmetric gradient (the mean of both frames', which converges in fewer steps than either).
struct PixelResidual {
  bool inside = false;
  double r = 0.0, gx = 0.0, gy = 0.0, a = 0.0;
};

// The older frame's bilinear interpolant and its exact derivatives at (x, y).
bool bilinear(const cv::Mat1f& image, double x, double y, double& value, double& dx, double& dy) {
  if (!(x >= 1.0 && y >= 1.0 && x < image.cols - 2.0 && y < image.rows - 2.0)) return false;
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double tx = x - x0, ty = y - y0;
  const float* r0 = image[y0];
  const float* r1 = image[y0 + 1];
  const double a00 = r0[x0], a01 = r0[x0 + 1], a10 = r1[x0], a11 = r1[x0 + 1];
  const double top = a00 + tx * (a01 - a00), bottom = a10 + tx * (a11 - a10);
  value = top + ty * (bottom - top);
  dx = (1.0 - ty) * (a01 - a00) + ty * (a11 - a10);
  dy = bottom - top;
  return true;
}

// The motion as the inverse map of the newer frame's pixels into the older one's.
struct InverseMap {
  double c, tx, ty, i00, i01, i10, i11;
  InverseMap(const ImageSimilarity& m, int n) : c(imageCentre(n)) {
    const double s = std::exp(m.log_zoom);
    const double cs = std::cos(m.rotation), sn = std::sin(m.rotation);
    // A(c + M^-1 (x - d - c)), M = (I + S) s R(theta), R = [cos sin; -sin cos] (y down,
    // counter-clockwise on screen): M^-1 = R^T (I + S)^-1 / s.
    const double r00 = cs / s, r01 = -sn / s, r10 = sn / s, r11 = cs / s;
    const double a = m.stretch_a, b = m.stretch_b;
    const double det = (1.0 + a) * (1.0 - a) - b * b;
    const double s00 = (1.0 - a) / det, s01 = -b / det, s10 = -b / det, s11 = (1.0 + a) / det;
    i00 = r00 * s00 + r01 * s10;
    i01 = r00 * s01 + r01 * s11;
    i10 = r10 * s00 + r11 * s10;
    i11 = r10 * s01 + r11 * s11;
    tx = m.translation.x;
    ty = m.translation.y;
  }
};

// The older frame at the point the newer frame's pixel (x, y) maps to: its bilinear value and
// derivatives; false outside it, and where either frame shows what its camera did not see
// (RefinementImage::seen): a levelled view's fill is the same in both frames wherever the scene
// moves, and read as texture it would pull the fit toward no motion.
bool olderAt(const RefinementImage& older, const RefinementImage& newer, const InverseMap& map, int x, int y,
             double& a, double& ax, double& ay) {
  if (!newer.seen.empty() && newer.seen(y, x) == 0) return false;
  const double qx = x - map.tx - map.c, qy = y - map.ty - map.c;
  const double sx = map.c + map.i00 * qx + map.i01 * qy, sy = map.c + map.i10 * qx + map.i11 * qy;
  if (!bilinear(older.smooth, sx, sy, a, ax, ay)) return false;
  if (older.seen.empty()) return true;
  // bilinear's four pixels (inside the frame, as it checked).
  const int x0 = static_cast<int>(sx), y0 = static_cast<int>(sy);
  const unsigned char* r0 = older.seen[y0];
  const unsigned char* r1 = older.seen[y0 + 1];
  return r0[x0] != 0 && r0[x0 + 1] != 0 && r1[x0] != 0 && r1[x0 + 1] != 0;
}

// Bilinear value of `image` at (x, y), the caller having checked that (x, y) and (x + 1, y + 1)
// lie inside.
inline double bilinearInside(const cv::Mat1f& image, double x, double y) {
  const int x0 = static_cast<int>(x), y0 = static_cast<int>(y);
  const double tx = x - x0, ty = y - y0;
  const float* r0 = image[y0] + x0;
  const float* r1 = r0 + image.step1();
  const double top = r0[0] + tx * (r0[1] - r0[0]);
  const double bottom = r1[0] + tx * (r1[1] - r1[0]);
  return top + ty * (bottom - top);
}

// The older frame's bilinear value at (sx, sy), where olderAt would read one (inside the frame,
// its four pixels seen); without the derivatives.
bool olderValue(const RefinementImage& older, double sx, double sy, double& value) {
  const cv::Mat1f& image = older.smooth;
  if (!(sx >= 1.0 && sy >= 1.0 && sx < image.cols - 2.0 && sy < image.rows - 2.0)) return false;
  if (!older.seen.empty()) {
    const int x0 = static_cast<int>(sx), y0 = static_cast<int>(sy);
    const unsigned char* s0 = older.seen[y0];
    const unsigned char* s1 = older.seen[y0 + 1];
    if (s0[x0] == 0 || s0[x0 + 1] == 0 || s1[x0] == 0 || s1[x0 + 1] == 0) return false;
  }
  value = bilinearInside(image, sx, sy);
  return true;
}

PixelResidual residualAt(const RefinementImage& older, const RefinementImage& newer, const InverseMap& map,
                         double gain, double bias, int x, int y) {
  PixelResidual p;
  double a = 0.0, ax = 0.0, ay = 0.0;
  if (!olderAt(older, newer, map, x, y, a, ax, ay)) return p;
  const float* row = newer.smooth[y];
  // The older frame's gradient at the source point maps to the newer's by M^-T = [i00 i10; i01 i11].
  p.gx = 0.5 * (gain * (map.i00 * ax + map.i10 * ay) + 0.5 * (row[x + 1] - row[x - 1]));
  p.gy = 0.5 * (gain * (map.i01 * ax + map.i11 * ay) + 0.5 * (newer.smooth(y + 1, x) - newer.smooth(y - 1, x)));
  p.r = row[x] - (gain * a + bias);
  p.a = a;
  p.inside = true;
  return p;
}

// The residuals' scale is read at the lower quartile of their magnitudes, not the median: over
// several depth layers the followed one may hold as little as a quarter of the pixels (the others
// move by pixels more), and a median then measures the other layers' misfit, under which the
// biweight rejects nothing and the steps fit one similarity's compromise of all the layers. On
// Gaussian residuals both read the same sigma.
constexpr double kScaleQuantile = 0.25;
// |r| of a Gaussian of sigma 1 has its lower quartile at sqrt(2) erf^-1(0.25).
constexpr double kQuartileOfUnitGaussian = 0.318639;

// The Gaussian sigma of the pixels that fit, from the absolute residuals `magnitudes` (reordered);
// negative when too few pixels took part.
double robustScale(std::vector<float>& magnitudes) {
  if (magnitudes.size() < kSimilarityParameters * 10u) return -1.0;
  auto quartile = magnitudes.begin() + static_cast<std::ptrdiff_t>(magnitudes.size() * kScaleQuantile);
  std::nth_element(magnitudes.begin(), quartile, magnitudes.end());
  if (*quartile > 0.0f) return *quartile / kQuartileOfUnitGaussian;
  // A quarter of the pixels fit exactly (flat texture in a noiseless frame): they tell no scale,
  // the median does.
  auto middle = magnitudes.begin() + magnitudes.size() / 2;
  std::nth_element(quartile, middle, magnitudes.end());
  return kMadToSigma * *middle;
}

// Tukey's biweight loss of one residual at the threshold `limit`: 0 for a perfect fit, 1 beyond.
double tukeyRho(double residual, double limit) {
  const double u = residual / limit;
  const double v = u * u < 1.0 ? 1.0 - u * u : 0.0;
  return 1.0 - v * v * v;
}

// The mean of Tukey's biweight loss (0 for a perfect fit, 1 beyond the threshold) over the
// absolute residuals `magnitudes` at the scale `sigma`: what the steps lower. The pixels that fit
// the best may do so whatever the motion (where the texture is flat, or near the centre for the
// zoom), so a scale read at their quartile says little of the fit as a whole; the loss at one
// scale counts every pixel.
double tukeyLoss(const std::vector<float>& magnitudes, double sigma) {
  if (magnitudes.empty()) return -1.0;
  const double limit = kTukey * sigma;
  double sum = 0.0;
  for (float m : magnitudes) sum += tukeyRho(m, limit);
  return sum / magnitudes.size();
}

// The image is cut into kLayerBlocks x kLayerBlocks blocks for the depth layers' test: at
// N = 512 and the refinement's stride, about 50 pixels of the grid each, enough to tell one shift
// from another where a pixel alone cannot (weak texture under sensor noise).
constexpr int kLayerBlocks = 8;
// A block leaves the refinement when another layer's shift fits it better by this many standard
// errors of the mean difference of the squared residuals (a paired test over its pixels). A
// periodic texture's alias fits as well as the true shift and removes nothing.
constexpr double kLayerEvidence = 3.0;
// Pixels a block needs for the test.
constexpr int kLayerBlockPixels = 10;

// Whether the mean of `count` paired differences (their sum and sum of squares) lies above zero
// by more than `evidence` of its standard errors.
bool clearlyPositive(double sum, double sum2, int count, double evidence) {
  const double mean = sum / count;
  const double variance = std::max(sum2 / count - mean * mean, 0.0);
  return mean > evidence * std::sqrt(variance / count);
}

// Which parts of the newer frame the refinement reads: the depth layers' test's blocks, and
// within the kept ones the cells that a finer test may leave out (areas of the frame).
class BlockMask {
 public:
  explicit BlockMask(int n) : n_(n), kept_(kLayerBlocks * kLayerBlocks, 1) {}
  int index(int x, int y) const { return (y * kLayerBlocks / n_) * kLayerBlocks + x * kLayerBlocks / n_; }
  bool kept(int x, int y) const {
    return kept_[index(x, y)] != 0 && (dropped_cells_.empty() || dropped_cells_[cell(x, y)] == 0);
  }
  void drop(int block) { kept_[block] = 0; }
  int dropped() const { return static_cast<int>(std::count(kept_.begin(), kept_.end(), 0)); }
  // Square cells of `size` px from `origin` (in x and y), none left out yet.
  void cellGrid(int origin, int size) {
    cell_origin_ = origin;
    cell_size_ = size;
    cells_per_side_ = (n_ - origin + size - 1) / size;
    dropped_cells_.assign(static_cast<std::size_t>(cells_per_side_ * cells_per_side_), 0);
  }
  // Leaves out the cell that holds the pixel (x, y).
  void dropCell(int x, int y) { dropped_cells_[cell(x, y)] = 1; }

 private:
  std::size_t cell(int x, int y) const {
    const int cx = std::clamp((x - cell_origin_) / cell_size_, 0, cells_per_side_ - 1);
    const int cy = std::clamp((y - cell_origin_) / cell_size_, 0, cells_per_side_ - 1);
    return static_cast<std::size_t>(cy * cells_per_side_ + cx);
  }

  int n_;
  std::vector<unsigned char> kept_;
  int cell_origin_ = 0, cell_size_ = 1, cells_per_side_ = 0;
  std::vector<unsigned char> dropped_cells_;
};

// The grid the refinement's tests and steps read: every `stride`-th pixel of every `stride`-th
// row where the taper is positive, row by row.
struct GridPixel {
  int x, y;
  float taper;
};

std::vector<GridPixel> taperedGrid(const std::vector<float>& taper, int stride) {
  const int n = static_cast<int>(taper.size());
  std::vector<GridPixel> grid;
  for (int y = stride / 2 + 1; y < n - 1; y += stride) {
    if (!(taper[y] > 0.0f)) continue;
    for (int x = stride / 2 + 1; x < n - 1; x += stride) {
      const float w = taper[y] * taper[x];
      if (w > 0.0f) grid.push_back({x, y, w});
    }
  }
  return grid;
}

// The blocks where the start's shift explains the frames no worse than the shift of any other
// depth layer in `other_layers` (at the start's rotation and zoom): over several depths the
// refinement must measure the followed layer's motion, and where the texture is weak against the
// noise, Tukey's biweight cannot tell a pixel of another layer from a noisy one, so those layers
// pull the zoom towards their own.
BlockMask followedLayerBlocks(const RefinementImage& older, const RefinementImage& newer, const std::vector<GridPixel>& grid,
                              const ImageSimilarity& start, const std::vector<cv::Point2d>& other_layers,
                              double bias) {
  const int n = newer.smooth.rows;
  BlockMask blocks(n);
  if (other_layers.empty()) return blocks;
  const InverseMap followed(start, n);
  std::vector<InverseMap> others;
  for (const cv::Point2d& shift : other_layers) {
    ImageSimilarity other = start;
    other.translation = shift;
    others.emplace_back(other, n);
  }
  // Per block and other layer: sums of d = r_followed^2 - r_other^2, of d^2, and the count.
  struct Sums {
    double d = 0.0, d2 = 0.0;
    int count = 0;
  };
  std::vector<Sums> sums(static_cast<std::size_t>(kLayerBlocks * kLayerBlocks) * others.size());
  for (const GridPixel& g : grid) {
    // residualAt's residual at gain 1, without its symmetric gradient.
    double a = 0.0, ax = 0.0, ay = 0.0;
    if (!olderAt(older, newer, followed, g.x, g.y, a, ax, ay)) continue;
    const double own = newer.smooth(g.y, g.x) - (a + bias);
    const std::size_t block = static_cast<std::size_t>(blocks.index(g.x, g.y));
    for (std::size_t i = 0; i < others.size(); ++i) {
      if (!olderAt(older, newer, others[i], g.x, g.y, a, ax, ay)) continue;
      const double other = newer.smooth(g.y, g.x) - (a + bias);
      const double d = own * own - other * other;
      Sums& s = sums[block * others.size() + i];
      s.d += d;
      s.d2 += d * d;
      ++s.count;
    }
  }
  for (int block = 0; block < kLayerBlocks * kLayerBlocks; ++block) {
    for (std::size_t i = 0; i < others.size(); ++i) {
      const Sums& s = sums[static_cast<std::size_t>(block) * others.size() + i];
      if (s.count < kLayerBlockPixels) continue;
      if (clearlyPositive(s.d, s.d2, s.count, kLayerEvidence)) {
        blocks.drop(block);
        break;
      }
    }
  }
  return blocks;
}

// The depth layers' test of followedLayerBlocks again, on a finer grain: a block holds parts of
// several surfaces wherever layers meet, a cell of kPixelCell x kPixelCell pixels of the sparse
// grid (about 27 px at N = 512) mostly one. A cell is tested on kPixelSamples samples around its
// centre, kPixelReach px to each side every kPixelStep px (the frames are smoothed over about a
// pixel, so their noises are nearly independent), and left out when another shift along the
// motion explains them better by kLayerEvidence standard errors. Walls and slopes lie between the
// layers, their shift varying with their height: besides the other layers' shifts,
// kShiftsBetweenLayers evenly spaced between the followed layer's and each other's are tried, or a
// wall would fit the followed layer no worse than any one layer's shift, and its texture, which
// turns as the camera passes it, would pull the rotation.
constexpr int kPixelCell = 3;
constexpr int kPixelReach = 4;
constexpr int kPixelStep = 2;
constexpr int kPixelSamples = (2 * kPixelReach / kPixelStep + 1) * (2 * kPixelReach / kPixelStep + 1);
constexpr int kShiftsBetweenLayers = 3;
// Shifts closer than this to the start's [px] are not tried: no other surface.
constexpr double kMinShiftApartPx = 1.0;
// After this many samples a shift that fits clearly worse (most shifts at most cells) is not
// followed further: the test's time goes to the shifts that may win.
constexpr int kEarlyLook = 10;

// The shifts the cells' test tries besides the start's: the other layers' and those between.
std::vector<cv::Point2d> triedShifts(const cv::Point2d& followed, const std::vector<cv::Point2d>& other_layers) {
  std::vector<cv::Point2d> shifts;
  for (const cv::Point2d& layer : other_layers) {
    for (int j = 1; j <= kShiftsBetweenLayers + 1; ++j) {
      const cv::Point2d shift = followed + (layer - followed) * (j / (kShiftsBetweenLayers + 1.0));
      if (cv::norm(shift - followed) > kMinShiftApartPx) shifts.push_back(shift);
    }
  }
  return shifts;
}

// Leaves out of `blocks` the cells (of kPixelCell x kPixelCell pixels of the grid every `stride`
// px) in kept blocks that one of `shifts` (at the start's rotation and zoom) explains better than
// the start's; returns how many.
int dropOtherSurfaceCells(const RefinementImage& older, const RefinementImage& newer, const std::vector<float>& taper,
                          const ImageSimilarity& start, const std::vector<cv::Point2d>& shifts, double bias,
                          int stride, BlockMask& blocks) {
  const int n = newer.smooth.rows;
  const int first = stride / 2 + 1;
  // A cell's area reaches half the grid's spacing beyond its outer pixels.
  blocks.cellGrid(first - stride / 2, kPixelCell * stride);
  int dropped = 0;
  if (shifts.empty()) return dropped;
  const InverseMap map(start, n);
  // A newer pixel's position in the older frame moves by I (d_start - d) under another shift d,
  // and by I o for a sample o px from the pixel: both the same everywhere.
  std::vector<cv::Point2d> shift_offsets;
  for (const cv::Point2d& d : shifts) {
    const double dx = map.tx - d.x, dy = map.ty - d.y;
    shift_offsets.emplace_back(map.i00 * dx + map.i01 * dy, map.i10 * dx + map.i11 * dy);
  }
  struct Sample {
    int dx, dy;
    double ox, oy;
  };
  std::vector<Sample> samples;
  double span = 1.0;  // how far a sample lies from the cell's centre in the older frame, plus a pixel
  for (int dy = -kPixelReach; dy <= kPixelReach; dy += kPixelStep) {
    for (int dx = -kPixelReach; dx <= kPixelReach; dx += kPixelStep) {
      const Sample o{dx, dy, map.i00 * dx + map.i01 * dy, map.i10 * dx + map.i11 * dy};
      samples.push_back(o);
      span = std::max({span, std::fabs(o.ox) + 1.0, std::fabs(o.oy) + 1.0});
    }
  }
  // Where the samples' bounding box lies inside the older frame and no pixel is unseen, they are
  // read without a check each.
  const auto clear = [&](double x, double y) {
    return older.seen.empty() && x - span >= 1.0 && y - span >= 1.0 && x + span < n - 2.0 && y + span < n - 2.0;
  };
  const auto olderSample = [&](double x, double y, bool checked, double& value) {
    if (checked) {
      value = bilinearInside(older.smooth, x, y);
      return true;
    }
    return olderValue(older, x, y, value);
  };
  double own[kPixelSamples];
  double newer_value[kPixelSamples];
  const int cell_span = (kPixelCell - 1) * stride;
  for (int y0 = first; y0 < n - 1; y0 += kPixelCell * stride) {
    const int y = y0 + cell_span / 2;  // the cell's centre
    if (y - kPixelReach < 1 || y + kPixelReach > n - 2 || !(taper[y] > 0.0f)) continue;
    for (int x0 = first; x0 < n - 1; x0 += kPixelCell * stride) {
      const int x = x0 + cell_span / 2;
      if (x - kPixelReach < 1 || x + kPixelReach > n - 2 || !(taper[x] > 0.0f) || !blocks.kept(x, y)) continue;
      const double qx = x - map.tx - map.c, qy = y - map.ty - map.c;
      const double sx = map.c + map.i00 * qx + map.i01 * qy, sy = map.c + map.i10 * qx + map.i11 * qy;
      const bool own_clear = clear(sx, sy) && newer.seen.empty();
      bool inside = true;
      for (int k = 0; k < kPixelSamples && inside; ++k) {
        const Sample& o = samples[k];
        double a = 0.0;
        inside = (newer.seen.empty() || newer.seen(y + o.dy, x + o.dx) != 0) &&
                 olderSample(sx + o.ox, sy + o.oy, own_clear, a);
        newer_value[k] = newer.smooth(y + o.dy, x + o.dx) - bias;
        own[k] = newer_value[k] - a;
      }
      if (!inside) continue;  // near an edge or the unseen: the blocks' choice stands
      for (const cv::Point2d& offset : shift_offsets) {
        const double bx = sx + offset.x, by = sy + offset.y;
        const bool shift_clear = clear(bx, by);
        double sum = 0.0, sum2 = 0.0;
        int k = 0;
        for (; k < kPixelSamples; ++k) {
          const Sample& o = samples[k];
          double a = 0.0;
          if (!olderSample(bx + o.ox, by + o.oy, shift_clear, a)) break;
          const double other = newer_value[k] - a;
          const double d = own[k] * own[k] - other * other;
          sum += d;
          sum2 += d * d;
          // The start's shift already fits clearly better: this one will not win.
          if (k + 1 == kEarlyLook && clearlyPositive(-sum, sum2, kEarlyLook, kLayerEvidence)) break;
        }
        if (k < kPixelSamples) continue;
        if (clearlyPositive(sum, sum2, kPixelSamples, kLayerEvidence)) {
          blocks.dropCell(x, y);
          ++dropped;
          break;
        }
      }
    }
  }
  return dropped;
}

// The pixels the refinement reads: those of the grid in a kept block and cell.
std::vector<GridPixel> keptPixels(const std::vector<GridPixel>& grid, const BlockMask& blocks) {
  std::vector<GridPixel> pixels;
  pixels.reserve(grid.size());
  for (const GridPixel& g : grid) {
    if (blocks.kept(g.x, g.y)) pixels.push_back(g);
  }
  return pixels;
}

// Variance of the noise of the symmetric gradient (refineSimilarity's PixelResidual) when the
// frames carry white noise of the given variances: both are smoothed by the refinement's
// Gaussian (autocorrelation R), the newer frame's gradient is a central difference, the older's
// the derivative of its bilinear interpolant (averaged over the sub-pixel position).
double gradientNoiseVariance(double older_variance, double newer_variance) {
  if (!(older_variance > 0.0) || !(newer_variance > 0.0)) return 0.0;
  struct Factors {
    double central = 0.0, bilinear = 0.0;  // per unit noise variance
  };
  static const Factors factors = [] {
    const cv::Mat kernel = cv::getGaussianKernel(kSmoothingTaps, kSmoothingSigma, CV_64F);  // makeRefinementImage's
    double r[3] = {0.0, 0.0, 0.0};  // the smoothing's 1-D autocorrelation at lags 0, 1, 2
    for (int d = 0; d < 3; ++d) {
      for (int i = 0; i + d < kernel.rows; ++i) r[d] += kernel.at<double>(i) * kernel.at<double>(i + d);
    }
    Factors f;
    f.central = 0.5 * (r[0] - r[2]) * r[0];
    f.bilinear = 2.0 * (r[0] - r[1]) * (2.0 * r[0] + r[1]) / 3.0;
    return f;
  }();
  return 0.25 * (older_variance * factors.bilinear + newer_variance * factors.central);
}

// The exposure's offset between the frames at `motion`: the mean difference of the grid's pixels
// both see (their differences are left in `residuals`);
// 0 when too few do. Left to the steps instead, an exposure change larger than the texture's
// contrast sets the first step's robust scale, under which the biweight keeps every depth layer
// and the steps fit their compromise.
double exposureOffset(const RefinementImage& older, const RefinementImage& newer, const std::vector<GridPixel>& grid,
                      const ImageSimilarity& motion, std::vector<float>& residuals) {
  const InverseMap map(motion, newer.smooth.rows);
  residuals.clear();
  for (const GridPixel& g : grid) {
    // residualAt's difference at gain 1 and bias 0, without its symmetric gradient.
    double a = 0.0, ax = 0.0, ay = 0.0;
    if (olderAt(older, newer, map, g.x, g.y, a, ax, ay)) residuals.push_back(static_cast<float>(newer.smooth(g.y, g.x) - a));
  }
  if (residuals.size() < kSimilarityParameters * 10u) return 0.0;
  double sum = 0.0;
  for (const float difference : residuals) sum += difference;
  return sum / static_cast<double>(residuals.size());
}

// One pixel's share of the normal equations of the first P parameters (a fixed count, so that
// the products unroll): its Jacobian j, weight w and residual r.
template <int P>
void accumulate(const Vector& j, double w, double r, Normal& normal, Vector& rhs) {
  for (int a = 0; a < P; ++a) {
    const double wj = w * j[a];
    rhs[a] += wj * r;
    for (int b = a; b < P; ++b) normal(a, b) += wj * j[b];
  }
}

// The gradients' noise adds var (U U^T + V V^T) to each pixel's expected normal matrix, with
// j_geometric = -(g_x U + g_y V); without its removal every step falls short. U and V are linear
// in the pixel's position (px, py) from the warp's centre, so the pixels' sum needs only the
// weighted moments of (1, px, py), gathered once per step.
class PositionMoments {
 public:
  void add(double w, double px, double py) {
    const double phi[3] = {1.0, px, py};
    for (int a = 0; a < 3; ++a) {
      for (int b = a; b < 3; ++b) m_(a, b) += w * phi[a] * phi[b];
    }
  }

  // normal(a, b) -= variance * sum_pixels w (U_a U_b + V_a V_b), a <= b < parameters.
  void subtractNoise(double variance, int parameters, Normal& normal) const {
    cv::Matx33d m = m_;
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < a; ++b) m(a, b) = m(b, a);
    }
    // U and V of each parameter as coefficients of (1, px, py):
    // U = (py, px, 1, 0, 0, 0, px, py), V = (-px, py, 0, 1, 0, 0, -py, px).
    static const cv::Vec3d kU[kParameters] = {{0, 0, 1}, {0, 1, 0}, {1, 0, 0}, {0, 0, 0},
                                              {0, 0, 0}, {0, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    static const cv::Vec3d kV[kParameters] = {{0, -1, 0}, {0, 0, 1}, {0, 0, 0}, {1, 0, 0},
                                              {0, 0, 0}, {0, 0, 0}, {0, 0, -1}, {0, 1, 0}};
    for (int a = 0; a < parameters; ++a) {
      const cv::Vec3d mu = m * kU[a], mv = m * kV[a];
      for (int b = a; b < parameters; ++b) normal(a, b) -= variance * (mu.dot(kU[b]) + mv.dot(kV[b]));
    }
  }

 private:
  cv::Matx33d m_ = cv::Matx33d::zeros();
};

}  // namespace

RefinementImage makeRefinementImage(const cv::Mat1f& grey, double noise_variance, const cv::Mat1b& seen) {
  RefinementImage image;
  if (grey.empty()) return image;
  if (!seen.empty() && seen.size() != grey.size()) {
    throw InputError("makeRefinementImage: the mask of what the camera saw is not the frame's size");
  }
  image.noise_variance = std::isfinite(noise_variance) && noise_variance > 0.0 ? noise_variance : 0.0;
  cv::GaussianBlur(grey, image.smooth, cv::Size(kSmoothingTaps, kSmoothingTaps), kSmoothingSigma, kSmoothingSigma, cv::BORDER_REFLECT);
  if (!seen.empty() && cv::countNonZero(seen) < static_cast<int>(seen.total())) {
    // A smoothed pixel mixes its neighbours within half the kernel, and the newer frame's
    // gradient (a central difference) reads one pixel further.
    const int reach = kSmoothingTaps / 2 + 1;
    const cv::Mat kernel = cv::getStructuringElement(cv::MORPH_RECT, cv::Size(2 * reach + 1, 2 * reach + 1));
    cv::erode(seen, image.seen, kernel);  // beyond the frame's edge counts as seen: bilinear bounds it
  }
  return image;
}

SimilarityRefinement refineSimilarity(const RefinementImage& older, const RefinementImage& newer,
                                      const ImageSimilarity& start, const std::vector<float>& taper,
                                      int iterations, int stride, bool fit_stretch,
                                      const std::vector<cv::Point2d>& other_layers) {
  const int n = newer.smooth.rows;
  if (older.empty() || newer.empty() || older.smooth.size() != newer.smooth.size() ||
      static_cast<int>(taper.size()) != n || newer.smooth.cols != n || stride < 1 ||
      (!older.seen.empty() && older.seen.size() != older.smooth.size()) ||
      (!newer.seen.empty() && newer.seen.size() != newer.smooth.size())) {
    throw InputError("refineSimilarity: frames or taper of different sizes");
  }
  SimilarityRefinement out;
  out.similarity = start;
  ImageSimilarity current = start;
  double gain = 1.0;
  std::vector<float> scratch;
  const std::vector<GridPixel> grid = taperedGrid(taper, stride);
  // The exposure's offset on the steps' own grid: on a sparser grid its estimate is noisy enough
  // to move the first step's robust weights on frames without any.
  double bias = exposureOffset(older, newer, grid, start, scratch);
  // The blocks are chosen at the start: after a step, which fits the layers' compromise, the other
  // layers' shifts fit the blocks less well than the start's did.
  BlockMask blocks = followedLayerBlocks(older, newer, grid, start, other_layers, bias);
  out.dropped_blocks = blocks.dropped();
  if (!other_layers.empty()) {
    out.dropped_cells = dropOtherSurfaceCells(older, newer, taper, start, triedShifts(start.translation, other_layers),
                                              bias, stride, blocks);
  }
  const std::vector<GridPixel> pixels = keptPixels(grid, blocks);
  // The residuals at the start, which set the first step's robust weights and scale the loss
  // that judges the fit, are the first step's residuals too.
  std::vector<PixelResidual> at_start;
  at_start.reserve(pixels.size());
  scratch.clear();
  {
    const InverseMap map(start, n);
    for (const GridPixel& g : pixels) {
      at_start.push_back(residualAt(older, newer, map, gain, bias, g.x, g.y));
      if (at_start.back().inside) scratch.push_back(static_cast<float>(std::fabs(at_start.back().r)));
    }
  }
  double sigma = robustScale(scratch);
  if (!(sigma > 0.0)) return out;
  out.residual_start = sigma;
  const double sigma_start = sigma;
  out.loss_start = tukeyLoss(scratch, sigma_start);
  const int parameters = fit_stretch ? kParameters : kSimilarityParameters;
  const double gradient_noise = gradientNoiseVariance(older.noise_variance, newer.noise_variance);
  for (int iteration = 0; iteration < iterations; ++iteration) {
    const InverseMap map(current, n);
    Normal normal = Normal::zeros();
    Vector rhs = Vector::all(0.0);
    PositionMoments moments;
    const double limit = kTukey * sigma;
    scratch.clear();
    for (std::size_t i = 0; i < pixels.size(); ++i) {
      const GridPixel& g = pixels[i];
      const PixelResidual p = iteration == 0 ? at_start[i] : residualAt(older, newer, map, gain, bias, g.x, g.y);
      if (!p.inside) continue;
      // The first pass's scale is the start's, already known.
      if (iteration > 0) scratch.push_back(static_cast<float>(std::fabs(p.r)));
      const double u = p.r / limit;
      if (!(u * u < 1.0)) continue;
      const double w = g.taper * (1.0 - u * u) * (1.0 - u * u);
      // Residual motion u = (delta I + omega J)(x - p) + dd about p = c + d, J v = (v_y, -v_x):
      // r ~ -g.u + d_gain A + d_bias.
      const double px = g.x - map.tx - map.c, py = g.y - map.ty - map.c;
      Vector j;
      j[0] = -(p.gx * py - p.gy * px);  // omega
      j[1] = -(p.gx * px + p.gy * py);  // delta (log zoom)
      j[2] = -p.gx;
      j[3] = -p.gy;
      j[4] = p.a;
      j[5] = 1.0;
      j[6] = -(p.gx * px - p.gy * py);  // stretch a: (px, -py)
      j[7] = -(p.gx * py + p.gy * px);  // stretch b: (py, px)
      if (fit_stretch) {
        accumulate<kParameters>(j, w, p.r, normal, rhs);
      } else {
        accumulate<kSimilarityParameters>(j, w, p.r, normal, rhs);
      }
      if (gradient_noise > 0.0) moments.add(w, px, py);
    }
    if (gradient_noise > 0.0) moments.subtractNoise(gradient_noise, parameters, normal);
    // The next step's scale: this pass's residuals (before its step); the first pass's are the
    // start's, whose scale is known.
    const double next = iteration == 0 ? sigma_start : robustScale(scratch);
    if (!(next > 0.0)) return out;
    sigma = next;
    for (int a = 0; a < kParameters; ++a) {
      for (int b = 0; b < a; ++b) normal(a, b) = normal(b, a);
    }
    for (int a = parameters; a < kParameters; ++a) normal(a, a) = 1.0;  // rhs 0: no step
    Vector step;
    if (!cv::solve(normal, rhs, step, cv::DECOMP_CHOLESKY)) return out;
    if (iteration + 1 == iterations) {
      // How closely the last step's pixels pin the rotation and the zoom: sigma^2 (J^T W J)^-1, the weights
      // read as inverse variances (an approximation for the biweight's; calibrated by its user).
      const Normal inverse = normal.inv(cv::DECOMP_CHOLESKY);
      out.rotation_sigma = std::sqrt(std::max(inverse(0, 0) * (sigma * sigma), 0.0));
      out.log_zoom_sigma = std::sqrt(std::max(inverse(1, 1) * (sigma * sigma), 0.0));
      if (fit_stretch) {
        const int index[3] = {0, 6, 7};  // rotation, stretch a, stretch b
        for (int a = 0; a < 3; ++a) {
          for (int b = 0; b < 3; ++b) {
            out.rotation_stretch_covariance(a, b) = inverse(index[a], index[b]) * (sigma * sigma);
          }
        }
      }
    }
    out.last_rotation_step = step[0];
    current.rotation += step[0];
    current.log_zoom += step[1];
    current.translation.x += step[2];
    current.translation.y += step[3];
    gain += step[4];
    bias += step[5];
    current.stretch_a += step[6];
    current.stretch_b += step[7];
    out.converged = std::fabs(step[0]) < kAngleTolerance && std::fabs(step[1]) < kAngleTolerance &&
                    std::fabs(step[2]) < kShiftTolerance && std::fabs(step[3]) < kShiftTolerance;
  }
  out.similarity = current;
  // The residuals at the refined motion: their scale, their loss at the start's scale, and the
  // loss's change from the start over the pixels inside at both, paired, so that the texture's
  // own spread of the loss cancels and what is left is the change's noise.
  const InverseMap map(current, n);
  const double limit = kTukey * sigma_start;
  double sum = 0.0, sum2 = 0.0;
  int paired = 0;
  scratch.clear();
  for (std::size_t i = 0; i < pixels.size(); ++i) {
    const PixelResidual p = residualAt(older, newer, map, gain, bias, pixels[i].x, pixels[i].y);
    if (!p.inside) continue;
    scratch.push_back(static_cast<float>(std::fabs(p.r)));
    if (!at_start[i].inside) continue;
    const double d = tukeyRho(p.r, limit) - tukeyRho(at_start[i].r, limit);
    sum += d;
    sum2 += d * d;
    ++paired;
  }
  out.pixels = static_cast<int>(scratch.size());
  out.residual_end = robustScale(scratch);
  if (out.residual_end >= 0.0) out.loss_end = tukeyLoss(scratch, sigma_start);
  if (paired >= kSimilarityParameters * 10) {  // as robustScale
    out.loss_change = sum / paired;
    out.loss_change_sigma = std::sqrt(std::max(sum2 / paired - out.loss_change * out.loss_change, 0.0) / (paired - 1));
  }
  return out;
}

}  // namespace oefmt
