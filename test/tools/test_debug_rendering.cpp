// SPDX-License-Identifier: GPL-3.0-or-later
// The ROS wrapper's rendering of correlation surfaces for the debug image topics.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include <opencv2/imgproc.hpp>

#include "oefmt/ros/estimate_messages.h"

namespace oefmt {
namespace {

// The heat map's colour of every pixel is the inferno colour of round(255 cbrt(|v| / max|v|)),
// up to one level (the table knows |v| / max|v| to 1/256).
TEST(DebugRendering, SurfaceHeatMapIsTheCubeRootColourMap) {
  cv::Mat1f surface(64, 96);
  cv::RNG rng(5);
  rng.fill(surface, cv::RNG::NORMAL, 0.0, 0.01);
  surface(10, 20) = -0.8f;  // the largest magnitude may be negative
  surface(30, 40) = 0.0f;
  surface(31, 41) = 1e-12f;
  const cv::Mat rendered = renderSurface(surface);
  ASSERT_EQ(rendered.type(), CV_8UC3);
  ASSERT_EQ(rendered.size(), surface.size());

  cv::Mat1b ramp(1, 256);
  for (int g = 0; g < 256; ++g) ramp(0, g) = static_cast<uchar>(g);
  cv::Mat colours;
  cv::applyColorMap(ramp, colours, cv::COLORMAP_INFERNO);
  int exact = 0;
  for (int r = 0; r < surface.rows; ++r) {
    for (int c = 0; c < surface.cols; ++c) {
      const int grey = static_cast<int>(std::lround(255.0 * std::cbrt(std::fabs(surface(r, c)) / 0.8)));
      const cv::Vec3b got = rendered.at<cv::Vec3b>(r, c);
      bool near = false;
      for (int g = std::max(0, grey - 1); g <= std::min(255, grey + 1); ++g) {
        near = near || got == colours.at<cv::Vec3b>(0, g);
      }
      EXPECT_TRUE(near) << "pixel (" << r << ", " << c << ") grey " << grey;
      exact += got == colours.at<cv::Vec3b>(0, grey);
    }
  }
  EXPECT_GT(exact, 0.9 * surface.total());
  EXPECT_EQ(rendered.at<cv::Vec3b>(10, 20), colours.at<cv::Vec3b>(0, 255));
  EXPECT_EQ(rendered.at<cv::Vec3b>(30, 40), colours.at<cv::Vec3b>(0, 0));
}

TEST(DebugRendering, ZeroNanAndEmptySurfacesRender) {
  EXPECT_TRUE(renderSurface(cv::Mat1f()).empty());
  const cv::Mat zero = renderSurface(cv::Mat1f::zeros(8, 8));
  ASSERT_EQ(zero.size(), cv::Size(8, 8));
  cv::Mat1f with_nan = cv::Mat1f::ones(8, 8);
  with_nan(3, 3) = std::numeric_limits<float>::quiet_NaN();
  const cv::Mat rendered = renderSurface(with_nan);
  ASSERT_EQ(rendered.size(), cv::Size(8, 8));
  EXPECT_EQ(rendered.at<cv::Vec3b>(3, 3), rendered.at<cv::Vec3b>(0, 0));  // the top colour
}

}  // namespace
}  // namespace oefmt
