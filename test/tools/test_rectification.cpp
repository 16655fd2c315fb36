// SPDX-License-Identifier: GPL-3.0-or-later
// The node's working frames (image_geometry's remap, oefmt/ros/rectification.h) are oefmt_offline's
// (the core's Undistorter::apply): the same camera gives the estimator the same frames.
#include <gtest/gtest.h>

#include <cmath>

#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"
#include "oefmt/ros/bag_io.h"
#include "oefmt/ros/rectification.h"
#include "oefmt/io/undistortion.h"

namespace oefmt {
namespace {

CameraParameters lens(int width, int height, double f, double k1, double k2, cv::Point2d offset = {}) {
  CameraParameters camera;
  camera.intrinsics = {f, f * 1.01, (width - 1) / 2.0 + offset.x, (height - 1) / 2.0 + offset.y, width, height};
  camera.distortion.k1 = k1;
  camera.distortion.k2 = k2;
  camera.distortion.p1 = 0.001;
  return camera;
}

// Texture with every scale: fine noise (the hardest case for two resamplings to agree) under
// smooth blobs.
cv::Mat1b texture(cv::Size size, int seed) {
  cv::RNG rng(seed);
  cv::Mat1f fine(size), coarse(size.height / 16 + 1, size.width / 16 + 1);
  rng.fill(fine, cv::RNG::UNIFORM, 0.0, 1.0);
  rng.fill(coarse, cv::RNG::UNIFORM, 0.0, 1.0);
  cv::Mat1f smooth;
  cv::resize(coarse, smooth, size, 0.0, 0.0, cv::INTER_CUBIC);
  cv::GaussianBlur(fine, fine, cv::Size(), 0.7);
  cv::Mat1b image;
  cv::Mat1f(0.4f * fine + 0.6f * smooth).convertTo(image, CV_8U, 255.0);
  return image;
}

struct Agreement {
  double max_difference = 0.0;  // [grey levels of 255]
  double mean_difference = 0.0;
};

Agreement compare(const CameraParameters& camera, const cv::Mat& frame, int working_size) {
  const Undistorter undistorter(camera, frame.size(), working_size, "camera_info");
  EXPECT_TRUE(undistorter.remaps());
  image_geometry::PinholeCameraModel model;
  EXPECT_TRUE(model.fromCameraInfo(workingFrameInfo(undistorter)));
  EXPECT_DOUBLE_EQ(model.fx(), undistorter.workingFx());
  const cv::Mat node = rectifyToWorkingFrame(undistorter, model, frame);
  const cv::Mat offline = undistorter.apply(frame);
  EXPECT_EQ(node.type(), CV_32FC1);
  EXPECT_EQ(node.size(), cv::Size(working_size, working_size));
  if (node.size() != offline.size() || node.type() != offline.type()) return {1e9, 1e9};
  EXPECT_TRUE(cv::checkRange(node)) << "the remap read outside the frame";
  const cv::Mat difference = cv::abs(node - offline) * 255.0;
  Agreement agreement;
  cv::minMaxLoc(difference, nullptr, &agreement.max_difference);
  agreement.mean_difference = cv::mean(difference)[0];
  return agreement;
}

TEST(Rectification, NodeAndOfflineMakeTheSameWorkingFrames) {
  struct Case {
    const char* what;
    CameraParameters camera;
    cv::Size size;
    int working_size;
  };
  const Case cases[] = {
      // a barrel lens, frames shrunk to the working scale first
      {"barrel, shrunk", lens(640, 480, 420.0, -0.2, 0.05), {640, 480}, 256},
      // the replay test's: a calibration of twice the images' resolution
      {"barrel, calibration at 2x", lens(1024, 1024, 900.0, -0.2, 0.05), {512, 512}, 512},
      // a pincushion lens with an off-centre principal point: the view is zoomed in to fit
      {"pincushion, off centre", lens(400, 300, 300.0, 0.15, 0.0, {9.0, -6.0}), {400, 300}, 384},
  };
  for (const Case& c : cases) {
    const cv::Mat1b frame = texture(c.size, c.working_size);
    const Agreement agreement = compare(c.camera, frame, c.working_size);
    // Both remaps sample the same positions, bicubic, rounded to 1/32 px: they differ only where
    // the two map computations (the core's in float, image_geometry's in double) round a
    // position to neighbouring steps, a few pixels in ten thousand, each by at most the
    // texture's gradient over 1/32 px.
    EXPECT_LE(agreement.max_difference, 1.0) << c.what;
    EXPECT_LE(agreement.mean_difference, 0.01) << c.what;
  }
}

TEST(Rectification, ColourAndSixteenBitFramesAgreeToo) {
  const CameraParameters camera = lens(320, 240, 210.0, -0.25, 0.06);
  cv::Mat1b b = texture({320, 240}, 1), g = texture({320, 240}, 2), r = texture({320, 240}, 3);
  cv::Mat colour;
  cv::merge(std::vector<cv::Mat>{b, g, r}, colour);
  EXPECT_LE(compare(camera, colour, 240).max_difference, 1.0);
  cv::Mat sixteen;
  b.convertTo(sixteen, CV_16U, 257.0);
  EXPECT_LE(compare(camera, sixteen, 240).max_difference, 1.0);
}

TEST(Rectification, MapsAreKeptWhileTheCameraStaysTheSame) {
  const Undistorter undistorter(lens(640, 480, 420.0, -0.2, 0.05), {640, 480}, 256);
  const sensor_msgs::CameraInfo info = workingFrameInfo(undistorter);
  EXPECT_EQ(info.width, 256u);
  EXPECT_EQ(info.height, 256u);
  EXPECT_EQ(info.distortion_model, "plumb_bob");
  EXPECT_EQ(info.P[0], undistorter.intrinsics().fx);
  EXPECT_EQ(info.P[2], undistorter.intrinsics().cx);
  image_geometry::PinholeCameraModel model;
  EXPECT_TRUE(model.fromCameraInfo(info));
  EXPECT_FALSE(model.fromCameraInfo(info));  // unchanged: image_geometry keeps its maps
  const Undistorter other(lens(640, 480, 420.0, -0.1, 0.0), {640, 480}, 256);
  EXPECT_TRUE(model.fromCameraInfo(workingFrameInfo(other)));
}

TEST(Rectification, ErrorsAsTheCoresUndistorter) {
  const Undistorter undistorter(lens(640, 480, 420.0, -0.2, 0.05), {640, 480}, 256);
  image_geometry::PinholeCameraModel model;
  model.fromCameraInfo(workingFrameInfo(undistorter));
  EXPECT_THROW(rectifyToWorkingFrame(undistorter, model, cv::Mat1b(480, 600)), InputError);
  EXPECT_THROW(rectifyToWorkingFrame(undistorter, model, cv::Mat1b(30, 40)), InputError);
  // Without distortion nothing is resampled: the frame is used as it is.
  CameraParameters camera = lens(640, 480, 420.0, 0.0, 0.0);
  camera.distortion = Distortion{};
  const Undistorter pinhole(camera, {640, 480}, 256);
  EXPECT_FALSE(pinhole.remaps());
  const cv::Mat1b frame = texture({640, 480}, 4);
  EXPECT_EQ(rectifyToWorkingFrame(pinhole, model, frame).data, frame.data);
  EXPECT_THROW(workingFrameInfo(pinhole), InputError);
}

}  // namespace
}  // namespace oefmt
