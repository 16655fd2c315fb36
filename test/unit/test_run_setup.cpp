// SPDX-License-Identifier: GPL-3.0-or-later
// The run set-up shared by oefmt_offline and the node: which camera and which starting altitude
// a run gets from the inputs it has, in the documented order of precedence.
#include <gtest/gtest.h>

#include "oefmt/io/run_setup.h"

namespace oefmt {
namespace {

CameraParameters calibration() {
  CameraParameters c;
  c.intrinsics.fx = 800.0;
  c.intrinsics.fy = 810.0;
  c.intrinsics.cx = 330.0;
  c.intrinsics.cy = 250.0;
  c.intrinsics.width = 640;
  c.intrinsics.height = 480;
  c.distortion.k1 = -0.2;
  return c;
}

TEST(RunSetup, TheOverrideFocalLengthKeepsTheCalibrationsCentreAndLens) {
  CameraSources sources;
  sources.calibration = calibration();
  sources.calibration_source = "cam_param.yaml";
  sources.override_fx = 400.0;
  sources.override_source = "--fx";
  sources.camera_fx = 999.0;
  const auto chosen = chooseCamera(sources, cv::Size(320, 240));  // half the calibration's size
  ASSERT_TRUE(chosen);
  EXPECT_EQ(chosen->source, "--fx");
  EXPECT_DOUBLE_EQ(chosen->camera.intrinsics.fx, 400.0);
  EXPECT_DOUBLE_EQ(chosen->camera.intrinsics.fy, 400.0);
  // (330 + 0.5) / 2 - 0.5: the calibration's centre mapped to the images' pixels.
  EXPECT_NEAR(chosen->camera.intrinsics.cx, 164.75, 1e-9);
  EXPECT_NEAR(chosen->camera.intrinsics.cy, 124.75, 1e-9);
  EXPECT_DOUBLE_EQ(chosen->camera.distortion.k1, -0.2);
}

TEST(RunSetup, TheCalibrationComesBeforeCameraFxAndCameraFxBeforeNothing) {
  CameraSources sources;
  sources.camera_fx = 450.0;
  sources.calibration = calibration();
  sources.calibration_source = "camera_info";
  auto chosen = chooseCamera(sources, cv::Size(640, 480));
  ASSERT_TRUE(chosen);
  EXPECT_EQ(chosen->source, "camera_info");
  EXPECT_DOUBLE_EQ(chosen->camera.intrinsics.fx, 800.0);

  sources.calibration.reset();
  chosen = chooseCamera(sources, cv::Size(640, 480));
  ASSERT_TRUE(chosen);
  EXPECT_EQ(chosen->source, "camera_fx");
  EXPECT_DOUBLE_EQ(chosen->camera.intrinsics.fx, 450.0);
  EXPECT_DOUBLE_EQ(chosen->camera.intrinsics.cx, 319.5);

  sources.camera_fx = 0.0;
  EXPECT_FALSE(chooseCamera(sources, cv::Size(640, 480)));
}

TEST(RunSetup, RectifiedFramesKeepTheCameraButLoseTheLens) {
  CameraSources sources;
  sources.calibration = calibration();
  sources.undistort = false;
  const auto chosen = chooseCamera(sources, cv::Size(640, 480));
  ASSERT_TRUE(chosen);
  EXPECT_DOUBLE_EQ(chosen->camera.intrinsics.fx, 800.0);
  EXPECT_DOUBLE_EQ(chosen->camera.distortion.k1, 0.0);
}

TEST(RunSetup, TheRunsOwnAltitudeComesBeforeTheConfiguredOne) {
  EXPECT_DOUBLE_EQ(chooseInitialAltitude(12.5, 20.0), 12.5);
  EXPECT_DOUBLE_EQ(chooseInitialAltitude(std::nullopt, 20.0), 20.0);
  EXPECT_DOUBLE_EQ(chooseInitialAltitude(std::nullopt, 0.0), 0.0) << "unknown stays unknown";
  EXPECT_DOUBLE_EQ(chooseInitialAltitude(0.0, 20.0), 20.0) << "no measurement is no altitude";
}

}  // namespace
}  // namespace oefmt
