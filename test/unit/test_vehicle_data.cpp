// SPDX-License-Identifier: GPL-3.0-or-later
// imu.txt and range.txt: written and read back, and every malformed line refused with the file
// and line named.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <functional>
#include <limits>
#include <string>

#include "oefmt/io/dataset.h"
#include "oefmt/io/vehicle_data.h"
#include "support/temp_dir.h"

namespace oefmt {
namespace {

std::string errorOf(const std::function<void()>& read) {
  try {
    read();
  } catch (const DatasetError& e) {
    return e.what();
  }
  return "";
}

TEST(VehicleData, ImuAndRangeFilesRoundTrip) {
  test::TempDir dir;
  std::vector<ImuSample> imu(3);
  for (int k = 0; k < 3; ++k) {
    imu[k].stamp = 1.0 + 0.005 * k;
    imu[k].orientation = Eigen::Quaterniond(Eigen::AngleAxisd(0.1 * k, Eigen::Vector3d(1, 2, 3).normalized()));
    imu[k].angular_velocity = Eigen::Vector3d(0.1, -0.2, 0.3 * k);
    imu[k].linear_acceleration = Eigen::Vector3d(0.5, -0.25, 9.81);
  }
  writeImuFile(dir / "imu.txt", imu, {"a header"});
  const std::vector<ImuSample> back = readImuFile(dir / "imu.txt");
  ASSERT_EQ(back.size(), 3u);
  for (int k = 0; k < 3; ++k) {
    EXPECT_NEAR(back[k].stamp, imu[k].stamp, 1e-6);
    EXPECT_LT(back[k].orientation.angularDistance(imu[k].orientation), 1e-8);
    EXPECT_TRUE(back[k].angular_velocity.isApprox(imu[k].angular_velocity, 1e-6));
    EXPECT_TRUE(back[k].linear_acceleration.isApprox(imu[k].linear_acceleration, 1e-5));
  }
  const std::vector<RangeSample> ranges = {{1.0, 10.25}, {1.2, std::numeric_limits<double>::infinity()}, {1.4, 9.5}};
  writeRangeFile(dir / "range.txt", ranges);
  const std::vector<RangeSample> read = readRangeFile(dir / "range.txt");
  ASSERT_EQ(read.size(), 3u);
  EXPECT_NEAR(read[0].range, 10.25, 1e-9);
  EXPECT_TRUE(std::isinf(read[1].range));
  EXPECT_NEAR(read[2].stamp, 1.4, 1e-9);
}

TEST(VehicleData, MalformedLinesAreRefusedWithFileAndLine) {
  test::TempDir dir;
  const auto imuError = [&](const std::string& text) {
    std::ofstream(dir / "imu.txt") << "# comment\n1.0 0 0 0 1 0 0 0 0 0 9.8\n" << text << "\n";
    return errorOf([&] { readImuFile(dir / "imu.txt"); });
  };
  EXPECT_NE(imuError("1.1 0 0 0 1 0 0 0 0 0").find("line 3: expected 11 numbers"), std::string::npos);
  EXPECT_NE(imuError("1.1 0 0 0 1 0 0 0 0 0 x").find("line 3"), std::string::npos);
  EXPECT_NE(imuError("1.0 0 0 0 1 0 0 0 0 0 9.8").find("after the previous"), std::string::npos);
  EXPECT_NE(imuError("1.1 0 0 0 0 0 0 0 0 0 9.8").find("zero quaternion"), std::string::npos);
  EXPECT_NE(imuError("1.1 0 0 0 1 inf 0 0 0 0 9.8").find("finite"), std::string::npos);
  EXPECT_TRUE(imuError("").empty());
  const auto rangeError = [&](const std::string& text) {
    std::ofstream(dir / "range.txt") << "1.0 10\n" << text << "\n";
    return errorOf([&] { readRangeFile(dir / "range.txt"); });
  };
  EXPECT_NE(rangeError("1.2 -3").find("line 2"), std::string::npos);
  EXPECT_NE(rangeError("1.2 nan").find("line 2"), std::string::npos);
  EXPECT_NE(rangeError("1.2").find("expected 2 numbers"), std::string::npos);
  EXPECT_TRUE(rangeError("1.2 inf").empty());
  EXPECT_NE(errorOf([&] { readRangeFile(dir / "missing.txt"); }).find("cannot open"), std::string::npos);
}

TEST(VehicleData, RangeAtTakesTheNearestReadingWithinTheTolerance) {
  const std::vector<RangeSample> readings = {{1.0, 10.0}, {1.2, 11.0}, {1.4, std::numeric_limits<double>::infinity()}};
  EXPECT_FALSE(rangeAt(readings, 1.09, 0.02).has_value());
  EXPECT_NEAR(rangeAt(readings, 1.09, 0.2)->range, 10.0, 1e-12);
  EXPECT_NEAR(rangeAt(readings, 1.11, 0.2)->range, 11.0, 1e-12);
  EXPECT_NEAR(rangeAt(readings, 1.2, 0.0)->range, 11.0, 1e-12);
  EXPECT_TRUE(std::isinf(rangeAt(readings, 1.41, 0.02)->range));
  EXPECT_FALSE(rangeAt({}, 1.0, 1.0).has_value());
  EXPECT_FALSE(rangeAt(readings, 0.5, 0.1).has_value());
}

}  // namespace
}  // namespace oefmt
