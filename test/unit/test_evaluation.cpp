// SPDX-License-Identifier: GPL-3.0-or-later
// Trajectory evaluation on known perturbations: similarity copies give zero error, noise gives
// the expected RMSE, scale errors give the expected drift; TUM files and association.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <random>

#include "support/temp_dir.h"
#include "oefmt/io/dataset.h"
#include "oefmt/error.h"
#include "oefmt/evaluation/evaluation.h"

namespace oefmt {
namespace {

// A closed wavy circle of n poses, 0.1 s apart, with some height change.
StampedTrajectory groundTruth(int n = 200) {
  StampedTrajectory truth;
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * M_PI * k / (n - 1);
    StampedPose pose;
    pose.stamp = 1.0 + 0.1 * k;
    pose.position = Eigen::Vector3d(78.0 * std::cos(a), 78.0 * std::sin(a) + 5.0 * std::sin(3 * a), 60.0 + 2.0 * std::sin(a));
    pose.orientation = Eigen::Quaterniond(Eigen::AngleAxisd(a, Eigen::Vector3d::UnitZ()));
    truth.push_back(pose);
  }
  return truth;
}

StampedTrajectory transformed(const StampedTrajectory& in, double scale, const Eigen::Matrix3d& rotation,
                       const Eigen::Vector3d& translation) {
  StampedTrajectory out = in;
  for (StampedPose& pose : out) {
    pose.position = scale * (rotation * pose.position) + translation;
    pose.orientation = Eigen::Quaterniond(rotation) * pose.orientation;
  }
  return out;
}

TEST(Evaluation, SimilarityCopyInThePlaneHasNoError) {
  const StampedTrajectory truth = groundTruth();
  const Eigen::Matrix3d yaw = Eigen::AngleAxisd(0.7, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const StampedTrajectory estimate = transformed(truth, 0.37, yaw, Eigen::Vector3d(5.0, -3.0, 2.0));
  EvaluationOptions options;
  const EvaluationResult result = evaluateTrajectory(estimate, truth, options);
  EXPECT_EQ(result.matched, truth.size());
  EXPECT_LT(result.ate.max, 1e-9);
  EXPECT_NEAR(result.alignment.scale, 1.0 / 0.37, 1e-9);
  EXPECT_NEAR(result.alignment.yaw(), -0.7, 1e-9);
  EXPECT_LT(result.drift_percent, 1e-9);
  EXPECT_LT(result.loop_error, 1e-9);
  EXPECT_EQ(result.drift.size(), 5u);
  EXPECT_GT(result.path_length, 2.0 * M_PI * 78.0);
}

TEST(Evaluation, SimilarityCopyInSpaceHasNoErrorIn3d) {
  const StampedTrajectory truth = groundTruth();
  const Eigen::Matrix3d rotation =
      (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitX()) * Eigen::AngleAxisd(-1.1, Eigen::Vector3d::UnitZ()))
          .toRotationMatrix();
  const StampedTrajectory estimate = transformed(truth, 2.5, rotation, Eigen::Vector3d(1.0, 2.0, 3.0));
  EvaluationOptions options;
  options.planar = false;
  EXPECT_LT(evaluateTrajectory(estimate, truth, options).ate.max, 1e-8);
  options.planar = true;  // a tilt cannot be undone in the plane
  EXPECT_GT(evaluateTrajectory(estimate, truth, options).ate.rmse, 1.0);
}

TEST(Evaluation, RigidAlignmentKeepsTheScaleError) {
  const StampedTrajectory truth = groundTruth();
  const StampedTrajectory estimate = transformed(truth, 1.1, Eigen::Matrix3d::Identity(), Eigen::Vector3d::Zero());
  EvaluationOptions options;
  options.with_scale = false;
  const EvaluationResult rigid = evaluateTrajectory(estimate, truth, options);
  EXPECT_EQ(rigid.alignment.scale, 1.0);
  EXPECT_GT(rigid.ate.rmse, 5.0);
  options.with_scale = true;
  EXPECT_LT(evaluateTrajectory(estimate, truth, options).ate.rmse, 1e-9);
}

TEST(Evaluation, AddedNoiseGivesTheExpectedRmse) {
  const StampedTrajectory truth = groundTruth(4000);
  StampedTrajectory estimate = truth;
  std::mt19937 random(42);
  std::normal_distribution<double> noise(0.0, 0.1);
  for (StampedPose& pose : estimate) pose.position += Eigen::Vector3d(noise(random), noise(random), noise(random));
  EvaluationOptions options;
  const EvaluationResult planar = evaluateTrajectory(estimate, truth, options);
  EXPECT_NEAR(planar.ate.rmse, 0.1 * std::sqrt(2.0), 0.005);  // two axes
  EXPECT_NEAR(planar.alignment.scale, 1.0, 1e-3);
  options.planar = false;
  EXPECT_NEAR(evaluateTrajectory(estimate, truth, options).ate.rmse, 0.1 * std::sqrt(3.0), 0.006);
}

TEST(Evaluation, ScaleErrorWithoutScaleAlignmentIsTenPercentDrift) {
  // A straight line walked 10 % too far: every displacement is 10 % long.
  StampedTrajectory truth, estimate;
  for (int k = 0; k <= 100; ++k) {
    StampedPose pose;
    pose.stamp = k;
    pose.position = Eigen::Vector3d(k, 0.0, 10.0);
    truth.push_back(pose);
    pose.position.x() *= 1.1;
    estimate.push_back(pose);
  }
  EvaluationOptions options;
  options.with_scale = false;
  const EvaluationResult result = evaluateTrajectory(estimate, truth, options);
  EXPECT_NEAR(result.drift_percent, 10.0, 1e-9);
  for (const DriftSegment& segment : result.drift) EXPECT_NEAR(segment.mean_percent, 10.0, 1e-9);
  EXPECT_NEAR(result.loop_error, 10.0, 1e-9);
  EXPECT_NEAR(result.loop_error_percent, 10.0, 1e-9);
  EXPECT_NEAR(result.ate.max, 5.0, 1e-9);  // centroids aligned: +-5 m at the ends
  EXPECT_NEAR(result.ate.median, 2.5, 1e-9);
}

TEST(Evaluation, AssociatesByTimeWithinTheToleranceOrByIndex) {
  const StampedTrajectory truth = groundTruth(50);
  StampedTrajectory estimate = truth;
  for (StampedPose& pose : estimate) pose.stamp += 0.004;
  estimate.erase(estimate.begin() + 10);  // a dropped frame
  EXPECT_EQ(associateByTime(estimate, truth, 0.01).size(), 49u);
  EXPECT_EQ(associateByTime(estimate, truth, 0.001).size(), 0u);
  const Association by_time = associateByTime(estimate, truth, 0.01);
  EXPECT_EQ(by_time[10].second, 11u);  // the gap is skipped, not shifted
  EXPECT_EQ(associateByIndex(estimate, truth).size(), 49u);

  EvaluationOptions options;
  options.time_tolerance = 0.001;
  EXPECT_THROW(evaluateTrajectory(estimate, truth, options), InputError);
  options.association = AssociationMode::kIndex;
  EXPECT_EQ(evaluateTrajectory(estimate, truth, options).matched, 49u);
}

TEST(Evaluation, RejectsDegenerateInput) {
  const StampedTrajectory truth = groundTruth(10);
  StampedTrajectory still = truth;
  for (StampedPose& pose : still) pose.position = Eigen::Vector3d(1.0, 2.0, 3.0);
  EXPECT_THROW(evaluateTrajectory(still, truth, EvaluationOptions{}), InputError);
  EXPECT_THROW(evaluateTrajectory(StampedTrajectory(truth.begin(), truth.begin() + 1), truth, EvaluationOptions{}), InputError);
}

TEST(Evaluation, RigidAlignmentOfACameraThatNeverMovedIsAShift) {
  // A spin in place: the truth stays at one point; so does a perfect estimate, elsewhere.
  StampedTrajectory truth = groundTruth(20);
  for (StampedPose& pose : truth) pose.position = Eigen::Vector3d(4.0, -2.0, 30.0);
  StampedTrajectory estimate = truth;
  for (StampedPose& pose : estimate) pose.position = Eigen::Vector3d(0.0, 0.0, 0.0);
  estimate[7].position = Eigen::Vector3d(0.3, 0.0, 0.0);  // one pose 0.3 m off the others
  EvaluationOptions options;
  options.with_scale = false;
  const EvaluationResult result = evaluateTrajectory(estimate, truth, options);
  EXPECT_NEAR(result.ate.max, 0.3 * 19.0 / 20.0, 1e-9);  // the means coincide after the shift
  for (StampedPose& pose : estimate) pose.position = Eigen::Vector3d(0.0, 0.0, 0.0);
  EXPECT_LT(evaluateTrajectory(estimate, truth, options).ate.max, 1e-9);
}

TEST(Evaluation, ErrorStatistics) {
  const ErrorStatistics stats = errorStatistics({4.0, 1.0, 3.0, 2.0});
  EXPECT_EQ(stats.count, 4u);
  EXPECT_DOUBLE_EQ(stats.median, 2.5);
  EXPECT_DOUBLE_EQ(stats.mean, 2.5);
  EXPECT_DOUBLE_EQ(stats.max, 4.0);
  EXPECT_DOUBLE_EQ(stats.rmse, std::sqrt(7.5));
  EXPECT_DOUBLE_EQ(errorStatistics({3.0, 1.0, 2.0}).median, 2.0);
}

TEST(Evaluation, TumFilesRoundTripAndReportBadLines) {
  test::TempDir dir;
  const StampedTrajectory truth = groundTruth(20);
  writeTum(dir / "a.tum", truth, {"a comment"});
  const StampedTrajectory read = readTum(dir / "a.tum");
  ASSERT_EQ(read.size(), truth.size());
  for (std::size_t k = 0; k < read.size(); ++k) {
    EXPECT_NEAR(read[k].stamp, truth[k].stamp, 1e-6);
    EXPECT_LT((read[k].position - truth[k].position).norm(), 1e-5);
    EXPECT_LT(read[k].orientation.angularDistance(truth[k].orientation), 1e-6);
  }
  std::ofstream(dir / "bad.tum") << "# header\n0 1 2 3 0 0 0 1\n1 1 2 3 0 0\n";
  try {
    readTum(dir / "bad.tum");
    ADD_FAILURE() << "no DatasetError";
  } catch (const DatasetError& e) {
    EXPECT_NE(std::string(e.what()).find("line 3"), std::string::npos) << e.what();
  }
  EXPECT_THROW(readTum(dir / "missing.tum"), DatasetError);
}

TEST(Evaluation, HeadingStepErrorsCountTheStepsOffByMoreThanTheThreshold) {
  const StampedTrajectory truth = groundTruth(50);
  // A constant yaw offset (any alignment) changes no step; turns added at two frames do.
  StampedTrajectory estimate = transformed(truth, 1.0, Eigen::AngleAxisd(1.0, Eigen::Vector3d::UnitZ()).toRotationMatrix(),
                                    Eigen::Vector3d::Zero());
  const auto turn = [&](std::size_t from, double radians) {
    for (std::size_t k = from; k < estimate.size(); ++k) {
      estimate[k].orientation = Eigen::Quaterniond(Eigen::AngleAxisd(radians, Eigen::Vector3d::UnitZ())) *
                                estimate[k].orientation;
    }
  };
  EvaluationOptions options;
  EXPECT_EQ(evaluateTrajectory(estimate, truth, options).heading_steps.over_threshold, 0u);
  EXPECT_LT(evaluateTrajectory(estimate, truth, options).heading_steps.max, 1e-9);
  turn(10, 3.0 * M_PI / 180.0);   // one step 3 degrees off
  turn(30, -1.0 * M_PI / 180.0);  // one step 1 degree off: below the threshold
  turn(40, 179.0 * M_PI / 180.0); // wraps: 179 degrees off
  const EvaluationResult result = evaluateTrajectory(estimate, truth, options);
  EXPECT_EQ(result.heading_steps.count, 49u);
  EXPECT_EQ(result.heading_steps.over_threshold, 2u);
  EXPECT_NEAR(result.heading_steps.max * 180.0 / M_PI, 179.0, 1e-6);
  options.heading_step_threshold = 0.5 * M_PI / 180.0;
  EXPECT_EQ(evaluateTrajectory(estimate, truth, options).heading_steps.over_threshold, 3u);
}

TEST(Evaluation, JsonLineHasEveryFigure) {
  const StampedTrajectory truth = groundTruth(30);
  EvaluationOptions options;
  const EvaluationResult result = evaluateTrajectory(truth, truth, options);
  const std::string json = evaluationJson(result, options);
  EXPECT_EQ(json.front(), '{');
  EXPECT_EQ(json.back(), '}');
  EXPECT_EQ(json.find('\n'), std::string::npos);
  for (const char* key : {"\"matched\":30", "\"alignment\":\"sim2\"", "\"ate\":{\"rmse\":", "\"median\":",
                          "\"drift_percent\":", "\"loop_error\":", "\"path_length\":",
                          "\"heading_steps\":{\"count\":29", "\"over_threshold\":0"}) {
    EXPECT_NE(json.find(key), std::string::npos) << key << " in " << json;
  }
  EXPECT_NE(evaluationTable(result, options).find("ATE rmse"), std::string::npos);
}

}  // namespace
}  // namespace oefmt
