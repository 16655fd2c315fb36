// SPDX-License-Identifier: GPL-3.0-or-later
// The three-frame local optimizer (doc/method.md, The local optimizer): pairs 1-2 and 0-2
// refined together so that the loop 0-1, 1-2, 0-2 closes, each measurement weighted by its sigma.
#pragma once

#include <string>
#include <vector>

#include "oefmt/enum_names.h"
#include "oefmt/estimation/length_source.h"
#include "oefmt/estimation/pair_motion.h"

namespace oefmt {

/// A scalar observation with its 1-sigma. Ignored unless value and sigma are finite, sigma > 0.
struct ScalarObservation {
  double value = 0.0;
  double sigma = 0.0;
  bool usable() const;
};

/// A 2-D observation of d [px of the newer frame] with its covariance [px^2].
struct VectorObservation {
  cv::Point2d value;
  cv::Matx22d covariance;
  bool usable() const;
};

/// Everything measured about one pair of the loop (1-2 or 0-2). Every observation becomes its own
/// residual block with its own robust loss.
struct PairObservations {
  ScalarObservation rotation;                   ///< theta [rad]
  std::vector<ScalarObservation> log_zoom;      ///< ln s: registration peak, PMS, ...
  /// The Cartesian translation d [px of the newer frame] with its covariance.
  cv::Point2d translation;
  cv::Matx22d translation_covariance;
  /// How d is used: kVector = both components; kDirection = only its direction (the cross-track
  /// component), when its length belongs to another depth layer; kNone = not at all.
  enum class TranslationUse { kVector, kDirection, kNone } translation_use = TranslationUse::kVector;
  std::vector<ScalarObservation> shift;         ///< |d| [px]: PMT prediction, followed layer, ...
  /// Further (weak) priors on d, e.g. the motion predicted from the previous pair.
  std::vector<VectorObservation> translation_priors;
  /// Which reading gave the length these observations hold d to (diagnostics; the optimizer does
  /// not read it).
  LengthSource length_source = LengthSource::kPeak;

  /// The observations of a registration: rotation, registration zoom and d (as kVector).
  static PairObservations fromMotion(const PairMotion& motion);
};

/// Loop closure errors t01 + t12 - t02 of the camera displacements, in frame 0.
struct LoopResiduals {
  cv::Point2d translation;  ///< [px of frame 0]
  double rotation = 0.0;    ///< theta01 + theta12 - theta02 [rad], wrapped
  double log_zoom = 0.0;    ///< ln s01 + ln s12 - ln s02
};

/// Loop errors of three pair motions.
LoopResiduals loopResiduals(const PairMotion& pair01, const PairMotion& pair12,
                            const PairMotion& pair02);

enum class RobustLoss { kNone, kHuber, kCauchy };
inline constexpr EnumName<RobustLoss> kRobustLossNames[] = {
    {RobustLoss::kNone, "none"}, {RobustLoss::kHuber, "huber"}, {RobustLoss::kCauchy, "cauchy"}};
inline const char* toString(RobustLoss loss) { return enumName(kRobustLossNames, loss); }

struct LocalOptimizerOptions {
  int max_iterations = 50;                 ///< Levenberg-Marquardt iterations
  RobustLoss robust_loss = RobustLoss::kCauchy;  ///< per residual block
  double loss_scale = 2.0;                 ///< residual (in sigmas) where the loss turns robust
  /// Sigma floors of the loop residuals (model error: parallax, rounding) added to the
  /// uncertainty the constant pair 0-1 brings into the loop.
  double loop_translation_sigma = 0.05;    ///< [px of frame 0]
  double loop_translation_sigma_relative = 0.002;  ///< of the loop's path length
  double loop_rotation_sigma = 2e-4;       ///< [rad]
  double loop_log_zoom_sigma = 1e-3;       ///< [ln s]: zoom biases differ between baselines
  /// Relative cost change (and relative step) that counts as converged. Robust losses make the
  /// last iterations converge linearly; 1e-6 stops within 1e-4 px of the minimum.
  double function_tolerance = 1e-6;

  /// Throws InputError naming the first invalid field.
  void validate() const;
};

enum class OptimizerStatus {
  kConverged,  ///< solved; the pairs are the optimized values
  kFallback,   ///< the solve failed or was not finite: the pairs are the measurements
  kSkipped,    ///< not run (no usable 0-2 pair, fmt/efmt mode): the pairs are the measurements
};
inline constexpr EnumName<OptimizerStatus> kOptimizerStatusNames[] = {
    {OptimizerStatus::kConverged, "converged"}, {OptimizerStatus::kFallback, "fallback"},
    {OptimizerStatus::kSkipped, "skipped"}};
inline const char* toString(OptimizerStatus status) { return enumName(kOptimizerStatusNames, status); }

/// Result of one local optimization. pair12/pair02 carry posterior sigmas when converged.
struct LoopSolution {
  PairMotion pair12;
  PairMotion pair02;
  OptimizerStatus status = OptimizerStatus::kSkipped;
  int iterations = 0;       ///< summed over all starting points
  int starts = 0;           ///< starting points solved (3 when the measured loop was open)
  double initial_cost = 0.0;  ///< of the winning start
  double final_cost = 0.0;
  LoopResiduals before;  ///< loop errors of the initial values
  LoopResiduals after;   ///< loop errors of the result
  std::string message;   ///< solver message when it fell back
};

/// Ceres Levenberg-Marquardt (DENSE_QR, 8 parameters) over the loop 0-1, 1-2, 0-2. Pair 0-1 is
/// constant (the previous step's optimized 1-2). Residuals, all divided by their sigmas:
/// - a prior per observation of pairs 1-2 and 0-2 (PairObservations);
/// - the translation loop t01 + t12 - t02 = 0 with the camera displacements in frame-0 pixels,
///   t_AB = -R(theta) d / s accumulated through the zooms and rotations of the chain;
/// - the rotation loop theta01 + theta12 - theta02 = 0 and the additive log-zoom loop.
/// The loops' sigmas come from pair 0-1's uncertainty plus the floors of the options. Observation
/// blocks carry the configured robust loss, the loop blocks a Huber loss (they are geometry and
/// must keep pulling). When the measured loop does not close (> 3 sigma), one observation is an
/// outlier and the cost is multi-modal: the solve is repeated from "1-2 recomputed from the loop"
/// and "0-2 recomputed from the loop", and the cheapest converged solution wins. Converged results
/// carry posterior sigmas ((J^T J)^-1 at the solution).
/// Never throws for numeric reasons: non-finite or degenerate inputs give kFallback.
class LocalOptimizer {
 public:
  explicit LocalOptimizer(const LocalOptimizerOptions& options);

  /// initial12/initial02: starting values (usually the measurements); they are also the
  /// fallback result.
  LoopSolution solve(const PairMotion& pair01, const PairObservations& observations12,
                     const PairObservations& observations02, const PairMotion& initial12,
                     const PairMotion& initial02) const;

  const LocalOptimizerOptions& options() const { return options_; }

 private:
  LocalOptimizerOptions options_;
};

}  // namespace oefmt
