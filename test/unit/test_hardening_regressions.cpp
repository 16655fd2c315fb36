// SPDX-License-Identifier: GPL-3.0-or-later
// Regressions for what the fuzz targets in fuzz/ found: each input below once broke a
// documented contract of the core.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <fstream>
#include <string>

#include <opencv2/core.hpp>

#include "support/temp_dir.h"
#include "oefmt/io/dataset.h"
#include "oefmt/error.h"
#include "oefmt/estimation/estimator_config.h"
#include "oefmt/io/config_file.h"
#include "oefmt/registration/image_prep.h"
#include "oefmt/registration/registration.h"
#include "support/fixtures.h"

namespace oefmt {
namespace {

using test::TempDir;

std::string writeFile(const TempDir& dir, const std::string& text) {
  const std::string path = dir / "input.yaml";
  std::ofstream(path, std::ios::binary) << text;
  return path;
}

// A YAML document that is a sequence, not a map: OpenCV asserts isMap() on the key lookup.
TEST(Regression, CameraParametersThatAreNotAMapThrowDatasetError) {
  TempDir dir;
  EXPECT_THROW(readCameraParameters(writeFile(dir, "%YAML 1.0\n-%YA")), DatasetError);
}

// An empty key inside a map: OpenCV's parser throws std::length_error, not cv::Exception.
TEST(Regression, EmptyYamlKeyThrowsTheDocumentedErrors) {
  TempDir dir;
  const std::string path = writeFile(dir, "%YAML:1.0\na:\n  b: 1\n  : 2\n");
  EXPECT_THROW(readCameraParameters(path), DatasetError);
  EXPECT_THROW(loadConfig(path), InputError);
}

// OpenCV's YAML reader never returned on this file (a NUL byte); it is refused before parsing.
TEST(Regression, ConfigurationWithNulByteIsRefused) {
  TempDir dir;
  const std::string path = writeFile(dir, std::string("%YAML 1.\n---e:t\nK\0\n---\n", 20));
  EXPECT_THROW(loadConfig(path), InputError);
}

// Float pixels near FLT_MAX overflowed to inf when resized to the working size.
TEST(Regression, FloatMaxPixelsStayFiniteWhenResized) {
  cv::Mat1f image(100, 100);
  for (int r = 0; r < image.rows; ++r) {
    for (int c = 0; c < image.cols; ++c) image(r, c) = ((r + c) % 3 == 0 ? 1.0f : -0.99f) * FLT_MAX;
  }
  const PreparedImage prepared = prepareImage(image, 64);
  EXPECT_TRUE(cv::checkRange(prepared.grey));
  EXPECT_TRUE(std::isfinite(prepared.texture));
}

// Float frames with huge values overflowed the single-precision spectra (NaN confidence, -inf
// peaks); scaled down, they register exactly like the same frames at ordinary intensities.
TEST(Regression, HugeFloatIntensitiesRegisterLikeOrdinaryOnes) {
  sim::ViewMotion motion;
  motion.shift = {3.0, -2.0};
  const test::ImagePair pair = test::warpedPair(motion, 128);
  const PairRegistration ordinary = test::registerImages(pair.older, pair.newer);
  const PairRegistration huge =
      test::registerImages(cv::Mat1f(pair.older * 1e36f), cv::Mat1f(pair.newer * 1e36f));
  ASSERT_TRUE(std::isfinite(huge.confidence));
  EXPECT_EQ(huge.status, ordinary.status);
  EXPECT_NEAR(huge.translation.x, ordinary.translation.x, 0.05);
  EXPECT_NEAR(huge.translation.y, ordinary.translation.y, 0.05);
  EXPECT_NEAR(huge.rotation, ordinary.rotation, 1e-3);
  EXPECT_NEAR(huge.zoom, ordinary.zoom, 1e-3);
}

}  // namespace
}  // namespace oefmt
