// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/estimation/local_optimizer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <utility>

#include <Eigen/Dense>
#include <ceres/ceres.h>

#include "oefmt/error.h"

namespace oefmt {
namespace {

// Parameter block layout of each pair: [theta, ln s, dx, dy].
constexpr int kBlock = 4;
constexpr int kTheta = 0, kLogZoom = 1, kDx = 2, kDy = 3;

// Very weak priors that keep every variable observable (and the posterior invertible) whatever
// observations are missing; far too weak to move a solution.
constexpr double kAnchorRotationSigma = 1.0;   // [rad]
constexpr double kAnchorLogZoomSigma = 1.0;
constexpr double kAnchorShiftSigma = 1000.0;  // [px]
// A loop whose whitened error exceeds this is "open": some observation is an outlier.
constexpr double kLoopOpenSigmas = 3.0;

using Mat2 = Eigen::Matrix2d;

Mat2 toEigen(const cv::Matx22d& m) {
  Mat2 e;
  e << m(0, 0), m(0, 1), m(1, 0), m(1, 1);
  return e;
}

cv::Matx22d toCv(const Mat2& e) { return {e(0, 0), e(0, 1), e(1, 0), e(1, 1)}; }

// W with W^T W = covariance^-1 (inverse Cholesky factor); a small ridge keeps it finite.
Mat2 whitening(const Mat2& covariance, double ridge) {
  Mat2 c = 0.5 * (covariance + covariance.transpose());
  c.diagonal().array() += ridge;
  Eigen::LLT<Mat2> llt(c);
  if (llt.info() != Eigen::Success) return Mat2::Identity() / std::sqrt(ridge);
  const Mat2 l = llt.matrixL();
  return l.inverse();
}

bool finite(const Mat2& m) { return m.allFinite(); }

// r = (x[index] - value) / sigma.
struct ScalarPrior {
  int index;
  double value, sigma;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    r[0] = (x[index] - value) / sigma;
    return true;
  }
};

// r_i = (x_i - value_i) / sigma_i for the whole block.
struct Anchor {
  std::array<double, kBlock> value, sigma;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    for (int i = 0; i < kBlock; ++i) r[i] = (x[i] - value[i]) / sigma[i];
    return true;
  }
};

// r = W (d - measured).
struct TranslationPrior {
  double mx, my;
  Mat2 w;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    const T ex = x[kDx] - mx, ey = x[kDy] - my;
    r[0] = w(0, 0) * ex + w(0, 1) * ey;
    r[1] = w(1, 0) * ex + w(1, 1) * ey;
    return true;
  }
};

// Cross-track distance of d from the measured direction, over its sigma.
struct DirectionPrior {
  double nx, ny;  // unit normal of the measured direction
  double sigma;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    r[0] = (nx * x[kDx] + ny * x[kDy]) / sigma;
    return true;
  }
};

// (|d| - value) / sigma; |d| smoothed at 0 so the derivative stays finite.
struct ShiftPrior {
  double value, sigma;
  template <typename T>
  bool operator()(const T* x, T* r) const {
    using std::sqrt;
    r[0] = (sqrt(x[kDx] * x[kDx] + x[kDy] * x[kDy] + T(1e-12)) - value) / sigma;
    return true;
  }
};

// Camera displacement loop in frame-0 pixels. t_AB = -R(theta) d / s; the 1-2 displacement is
// carried into frame 0 through pair 0-1's rotation and zoom. r = W (t01 + t12 - t02).
struct TranslationLoop {
  double t01x, t01y;          // constant displacement of pair 0-1
  double theta01, log_zoom01;
  Mat2 w;
  template <typename T>
  bool operator()(const T* x12, const T* x02, T* r) const {
    using std::cos;
    using std::exp;
    using std::sin;
    const T a12 = theta01 + x12[kTheta];
    const T k12 = -exp(-log_zoom01 - x12[kLogZoom]);
    const T t12x = k12 * (cos(a12) * x12[kDx] - sin(a12) * x12[kDy]);
    const T t12y = k12 * (sin(a12) * x12[kDx] + cos(a12) * x12[kDy]);
    const T k02 = -exp(-x02[kLogZoom]);
    const T t02x = k02 * (cos(x02[kTheta]) * x02[kDx] - sin(x02[kTheta]) * x02[kDy]);
    const T t02y = k02 * (sin(x02[kTheta]) * x02[kDx] + cos(x02[kTheta]) * x02[kDy]);
    const T ex = t01x + t12x - t02x;
    const T ey = t01y + t12y - t02y;
    r[0] = w(0, 0) * ex + w(0, 1) * ey;
    r[1] = w(1, 0) * ex + w(1, 1) * ey;
    return true;
  }
};

// r = (constant + x12[index] - x02[index]) / sigma: the rotation and log-zoom loops.
struct AdditiveLoop {
  int index;
  double constant, sigma;
  template <typename T>
  bool operator()(const T* x12, const T* x02, T* r) const {
    r[0] = (constant + x12[index] - x02[index]) / sigma;
    return true;
  }
};

// A finite copy: non-finite values become "no motion" with anchor-sized sigmas.
PairMotion sanitised(const PairMotion& m) {
  if (m.finite()) return m;
  PairMotion out;
  const auto keep = [](double v, double fallback) { return std::isfinite(v) ? v : fallback; };
  out.rotation = keep(m.rotation, 0.0);
  out.log_zoom = keep(m.log_zoom, 0.0);
  out.translation = {keep(m.translation.x, 0.0), keep(m.translation.y, 0.0)};
  out.rotation_sigma = kAnchorRotationSigma;
  out.log_zoom_sigma = kAnchorLogZoomSigma;
  out.translation_covariance = cv::Matx22d::eye() * (kAnchorShiftSigma * kAnchorShiftSigma);
  return out;
}

cv::Point2d displacement(const PairMotion& m) {
  return -rotateImageVector(m.translation, m.rotation) * std::exp(-m.log_zoom);
}

ceres::LossFunction* makeLoss(RobustLoss loss, double scale) {
  switch (loss) {
    case RobustLoss::kHuber: return new ceres::HuberLoss(scale);
    case RobustLoss::kCauchy: return new ceres::CauchyLoss(scale);
    case RobustLoss::kNone: return nullptr;
  }
  return nullptr;
}

std::array<double, kBlock> toBlock(const PairMotion& m) {
  return {m.rotation, m.log_zoom, m.translation.x, m.translation.y};
}

// Adds the priors of one pair's observations to `problem` on `block`.
void addPriors(ceres::Problem& problem, double* block, const PairObservations& obs,
               const LocalOptimizerOptions& options) {
  const auto loss = [&] { return makeLoss(options.robust_loss, options.loss_scale); };
  const auto scalar = [&](int index, double value, double sigma, ceres::LossFunction* l) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ScalarPrior, 1, kBlock>(
                                 new ScalarPrior{index, value, sigma}),
                             l, block);
  };
  if (obs.rotation.usable()) {
    // Unwrapped next to the starting value: the residual must not jump by 2 pi.
    const double value = block[kTheta] + wrapToPi(obs.rotation.value - block[kTheta]);
    scalar(kTheta, value, obs.rotation.sigma, loss());
  }
  for (const ScalarObservation& z : obs.log_zoom) {
    if (z.usable()) scalar(kLogZoom, z.value, z.sigma, loss());
  }
  const Mat2 covariance = toEigen(obs.translation_covariance);
  const bool translation_finite = std::isfinite(obs.translation.x) &&
                                  std::isfinite(obs.translation.y) && finite(covariance);
  if (translation_finite && obs.translation_use == PairObservations::TranslationUse::kVector) {
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<TranslationPrior, 2, kBlock>(
                                 new TranslationPrior{obs.translation.x, obs.translation.y,
                                                      whitening(covariance, 1e-6)}),
                             loss(), block);
  } else if (translation_finite &&
             obs.translation_use == PairObservations::TranslationUse::kDirection) {
    const double length = std::hypot(obs.translation.x, obs.translation.y);
    if (length > 1e-6) {
      const Eigen::Vector2d normal(-obs.translation.y / length, obs.translation.x / length);
      const double sigma = std::sqrt(std::max(normal.dot(covariance * normal), 0.0)) + 1e-3;
      problem.AddResidualBlock(new ceres::AutoDiffCostFunction<DirectionPrior, 1, kBlock>(
                                   new DirectionPrior{normal.x(), normal.y(), sigma}),
                               loss(), block);
    }
  }
  for (const VectorObservation& v : obs.translation_priors) {
    if (!v.usable()) continue;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<TranslationPrior, 2, kBlock>(
                                 new TranslationPrior{v.value.x, v.value.y,
                                                      whitening(toEigen(v.covariance), 1e-6)}),
                             loss(), block);
  }
  for (const ScalarObservation& s : obs.shift) {
    if (!s.usable()) continue;
    problem.AddResidualBlock(new ceres::AutoDiffCostFunction<ShiftPrior, 1, kBlock>(
                                 new ShiftPrior{s.value, s.sigma}),
                             loss(), block);
  }
  // Anchors, without a robust loss.
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<Anchor, kBlock, kBlock>(new Anchor{
                               {block[kTheta], block[kLogZoom], block[kDx], block[kDy]},
                               {kAnchorRotationSigma, kAnchorLogZoomSigma, kAnchorShiftSigma,
                                kAnchorShiftSigma}}),
                           nullptr, block);
}

// Fills the sigmas of `m` from the posterior covariance of its block (rows offset..offset+3).
void setPosterior(const Eigen::MatrixXd& covariance, int offset, PairMotion& m) {
  m.rotation_sigma = std::sqrt(std::max(covariance(offset + kTheta, offset + kTheta), 0.0));
  m.log_zoom_sigma = std::sqrt(std::max(covariance(offset + kLogZoom, offset + kLogZoom), 0.0));
  const Mat2 d = covariance.block<2, 2>(offset + kDx, offset + kDx);
  m.translation_covariance = toCv(0.5 * (d + d.transpose()));
}

// Posterior covariance (J^T J)^-1 of the parameters at the solution; false if not finite.
bool posteriorCovariance(ceres::Problem& problem, double* x12, double* x02, Eigen::MatrixXd& out) {
  ceres::Problem::EvaluateOptions evaluate;
  evaluate.parameter_blocks = {x12, x02};
  ceres::CRSMatrix jacobian;
  if (!problem.Evaluate(evaluate, nullptr, nullptr, nullptr, &jacobian)) return false;
  Eigen::MatrixXd j = Eigen::MatrixXd::Zero(jacobian.num_rows, jacobian.num_cols);
  for (int row = 0; row < jacobian.num_rows; ++row) {
    for (int k = jacobian.rows[row]; k < jacobian.rows[row + 1]; ++k) {
      j(row, jacobian.cols[k]) = jacobian.values[k];
    }
  }
  const Eigen::MatrixXd h = j.transpose() * j;
  Eigen::LDLT<Eigen::MatrixXd> ldlt(h);
  if (ldlt.info() != Eigen::Success) return false;
  out = ldlt.solve(Eigen::MatrixXd::Identity(h.rows(), h.cols()));
  return out.allFinite() && (out.diagonal().array() >= 0.0).all();
}

}  // namespace

bool ScalarObservation::usable() const {
  return std::isfinite(value) && std::isfinite(sigma) && sigma > 0.0;
}

bool VectorObservation::usable() const {
  return std::isfinite(value.x) && std::isfinite(value.y) && finite(toEigen(covariance)) &&
         covariance(0, 0) > 0.0 && covariance(1, 1) > 0.0;
}

PairObservations PairObservations::fromMotion(const PairMotion& motion) {
  PairObservations obs;
  obs.rotation = {motion.rotation, motion.rotation_sigma};
  obs.log_zoom.push_back({motion.log_zoom, motion.log_zoom_sigma});
  obs.translation = motion.translation;
  obs.translation_covariance = motion.translation_covariance;
  return obs;
}

LoopResiduals loopResiduals(const PairMotion& p01, const PairMotion& p12, const PairMotion& p02) {
  LoopResiduals r;
  const cv::Point2d t01 = displacement(p01);
  // Pair 1-2's displacement is in frame-1 pixels and axes: carry it into frame 0.
  const cv::Point2d t12 = rotateImageVector(displacement(p12), p01.rotation) * std::exp(-p01.log_zoom);
  r.translation = t01 + t12 - displacement(p02);
  r.rotation = wrapToPi(p01.rotation + p12.rotation - p02.rotation);
  r.log_zoom = p01.log_zoom + p12.log_zoom - p02.log_zoom;
  return r;
}

void LocalOptimizerOptions::validate() const {
  requireParameter(max_iterations >= 1 && max_iterations <= 1000, "max_iterations", "must be in [1, 1000]");
  requireParameter(std::isfinite(loss_scale) && loss_scale > 0.0, "loss_scale", "must be > 0");
  requireParameter(std::isfinite(loop_translation_sigma) && loop_translation_sigma > 0.0, "loop_translation_sigma",
                   "must be > 0 px");
  requireParameter(std::isfinite(loop_translation_sigma_relative) && loop_translation_sigma_relative >= 0.0,
                   "loop_translation_sigma_relative", "must be >= 0");
  requireParameter(std::isfinite(loop_rotation_sigma) && loop_rotation_sigma > 0.0, "loop_rotation_sigma",
                   "must be > 0 rad");
  requireParameter(std::isfinite(loop_log_zoom_sigma) && loop_log_zoom_sigma > 0.0, "loop_log_zoom_sigma",
                   "must be > 0");
  requireParameter(std::isfinite(function_tolerance) && function_tolerance > 0.0 && function_tolerance < 1.0,
                   "function_tolerance", "must be in (0, 1)");
}

LocalOptimizer::LocalOptimizer(const LocalOptimizerOptions& options) : options_(options) {
  options_.validate();
}

LoopSolution LocalOptimizer::solve(const PairMotion& pair01, const PairObservations& obs12,
                                   const PairObservations& obs02, const PairMotion& initial12,
                                   const PairMotion& initial02) const {
  LoopSolution solution;
  solution.pair12 = sanitised(initial12);
  solution.pair02 = sanitised(initial02);
  solution.status = OptimizerStatus::kFallback;
  if (!pair01.finite() || !initial12.finite() || !initial02.finite()) {
    solution.message = "non-finite input";
    return solution;
  }
  solution.before = loopResiduals(pair01, initial12, initial02);
  solution.after = solution.before;

  std::array<double, kBlock> x12 = toBlock(initial12);
  std::array<double, kBlock> x02 = toBlock(initial02);
  ceres::Problem problem;
  problem.AddParameterBlock(x12.data(), kBlock);
  problem.AddParameterBlock(x02.data(), kBlock);
  addPriors(problem, x12.data(), obs12, options_);
  addPriors(problem, x02.data(), obs02, options_);

  // The loops' uncertainty: pair 0-1 is held constant, so its own sigmas enter here, plus a
  // model floor growing with the path length.
  const cv::Point2d t01 = displacement(pair01);
  const cv::Point2d t12 =
      rotateImageVector(displacement(initial12), pair01.rotation) * std::exp(-pair01.log_zoom);
  const cv::Point2d t02 = displacement(initial02);
  const Eigen::Vector2d head(t01.x + t12.x, t01.y + t12.y);  // moves with theta01 and ln s01
  const Eigen::Vector2d head_turned(-head.y(), head.x());
  const double c = std::cos(pair01.rotation), s = std::sin(pair01.rotation);
  Mat2 r01;
  r01 << c, -s, s, c;
  const double floor = options_.loop_translation_sigma +
                       options_.loop_translation_sigma_relative *
                           (cv::norm(t01) + cv::norm(t12) + cv::norm(t02));
  const double inv_zoom01 = std::exp(-pair01.log_zoom);
  Mat2 loop_covariance = r01 * toEigen(pair01.translation_covariance) * r01.transpose() *
                             inv_zoom01 * inv_zoom01 +
                         pair01.rotation_sigma * pair01.rotation_sigma * head_turned *
                             head_turned.transpose() +
                         pair01.log_zoom_sigma * pair01.log_zoom_sigma * head * head.transpose();
  loop_covariance.diagonal().array() += floor * floor;
  const Mat2 loop_whitening = whitening(loop_covariance, 1e-9);
  const double rotation_loop_sigma = std::hypot(pair01.rotation_sigma, options_.loop_rotation_sigma);
  const double zoom_loop_sigma = std::hypot(pair01.log_zoom_sigma, options_.loop_log_zoom_sigma);
  // Rotation loop constant chosen so the loop starts within (-pi, pi].
  const double theta_loop = solution.before.rotation - (x12[kTheta] - x02[kTheta]);
  // The loops are geometry, exact up to the floors: a Huber loss (convex) keeps them pulling
  // however large they get, so that a single outlying observation loses against the loop instead
  // of the loop being written off.
  const auto loop_loss = [&] {
    return options_.robust_loss == RobustLoss::kNone ? nullptr
                                                     : new ceres::HuberLoss(options_.loss_scale);
  };
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<TranslationLoop, 2, kBlock, kBlock>(
                               new TranslationLoop{t01.x, t01.y, pair01.rotation, pair01.log_zoom,
                                                   loop_whitening}),
                           loop_loss(), x12.data(), x02.data());
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<AdditiveLoop, 1, kBlock, kBlock>(
                               new AdditiveLoop{kTheta, theta_loop, rotation_loop_sigma}),
                           loop_loss(), x12.data(), x02.data());
  problem.AddResidualBlock(new ceres::AutoDiffCostFunction<AdditiveLoop, 1, kBlock, kBlock>(
                               new AdditiveLoop{kLogZoom, pair01.log_zoom, zoom_loop_sigma}),
                           loop_loss(), x12.data(), x02.data());

  // Starting points. When the measured loop does not close, one pair holds an outlier and the
  // robust priors make the cost multi-modal: also start from "1-2 is wrong" (1-2 recomputed from
  // the loop) and "0-2 is wrong", and keep the cheapest converged solution.
  std::vector<std::pair<std::array<double, kBlock>, std::array<double, kBlock>>> starts;
  starts.emplace_back(x12, x02);
  const Eigen::Vector2d loop_error(solution.before.translation.x, solution.before.translation.y);
  const bool loop_open = (loop_whitening * loop_error).norm() > kLoopOpenSigmas ||
                         std::fabs(solution.before.rotation) > kLoopOpenSigmas * rotation_loop_sigma ||
                         std::fabs(solution.before.log_zoom) > kLoopOpenSigmas * zoom_loop_sigma;
  if (loop_open) {
    PairMotion closed12 = initial12;  // 1-2 = (0-2) - (0-1)
    closed12.rotation = initial02.rotation - theta_loop;
    closed12.log_zoom = initial02.log_zoom - pair01.log_zoom;
    const cv::Point2d t12_frame1 = rotateImageVector(t02 - t01, -pair01.rotation) * std::exp(pair01.log_zoom);
    closed12.translation = -rotateImageVector(t12_frame1, -closed12.rotation) * std::exp(closed12.log_zoom);
    PairMotion closed02 = initial02;  // 0-2 = (0-1) + (1-2)
    closed02.rotation = theta_loop + initial12.rotation;
    closed02.log_zoom = pair01.log_zoom + initial12.log_zoom;
    closed02.translation = -rotateImageVector(t01 + t12, -closed02.rotation) * std::exp(closed02.log_zoom);
    starts.emplace_back(toBlock(closed12), x02);
    starts.emplace_back(x12, toBlock(closed02));
    starts.back().second[kTheta] = closed02.rotation;  // keep the unwrapped value
    starts[1].first[kTheta] = closed12.rotation;
  }

  ceres::Solver::Options solver;
  solver.linear_solver_type = ceres::DENSE_QR;
  solver.max_num_iterations = options_.max_iterations;
  solver.function_tolerance = options_.function_tolerance;
  solver.parameter_tolerance = options_.function_tolerance;
  solver.num_threads = 1;
  solver.logging_type = ceres::SILENT;
  solver.minimizer_progress_to_stdout = false;
  const auto all_finite = [](const std::array<double, kBlock>& v) {
    return std::all_of(v.begin(), v.end(), [](double e) { return std::isfinite(e); });
  };
  bool solved = false;
  std::array<double, kBlock> best12{}, best02{};
  double best_cost = std::numeric_limits<double>::infinity();
  for (const auto& start : starts) {
    x12 = start.first;
    x02 = start.second;
    ceres::Solver::Summary summary;
    ceres::Solve(solver, &problem, &summary);
    ++solution.starts;
    solution.iterations += static_cast<int>(summary.iterations.size());
    const bool ok = summary.termination_type == ceres::CONVERGENCE && all_finite(x12) &&
                    all_finite(x02) && std::isfinite(summary.final_cost);
    if (!ok) {
      solution.message = summary.message.empty() ? "not converged" : summary.message;
      continue;
    }
    if (summary.final_cost < best_cost) {
      best_cost = summary.final_cost;
      best12 = x12;
      best02 = x02;
      solution.initial_cost = summary.initial_cost;
      solution.final_cost = summary.final_cost;
      solved = true;
    }
  }
  if (!solved) return solution;
  x12 = best12;
  x02 = best02;
  solution.message.clear();
  Eigen::MatrixXd covariance;
  if (!posteriorCovariance(problem, x12.data(), x02.data(), covariance)) {
    solution.message = "posterior covariance not finite";
    return solution;
  }
  PairMotion out12, out02;
  out12.rotation = wrapToPi(x12[kTheta]);
  out12.log_zoom = x12[kLogZoom];
  out12.translation = {x12[kDx], x12[kDy]};
  out02.rotation = wrapToPi(x02[kTheta]);
  out02.log_zoom = x02[kLogZoom];
  out02.translation = {x02[kDx], x02[kDy]};
  setPosterior(covariance, 0, out12);
  setPosterior(covariance, kBlock, out02);
  if (!out12.finite() || !out02.finite()) {
    solution.message = "non-finite solution";
    return solution;
  }
  solution.pair12 = out12;
  solution.pair02 = out02;
  solution.status = OptimizerStatus::kConverged;
  solution.after = loopResiduals(pair01, out12, out02);
  return solution;
}

}  // namespace oefmt
