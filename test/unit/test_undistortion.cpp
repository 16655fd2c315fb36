// SPDX-License-Identifier: GPL-3.0-or-later
// The frames' undistortion (oefmt/undistortion.h), against the lens model the simulator renders
// with (sim::distortNormalised): a grid of dots drawn through a distorted lens comes out where an
// ideal pinhole of the reported intrinsics puts it (so its rows and columns are straight again),
// every output pixel comes from inside the input, a calibration of another resolution is mapped,
// and unusable calibrations are refused in one line.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"
#include "oefmt/sim/camera_model.h"
#include "oefmt/io/undistortion.h"

namespace oefmt {
namespace {

// Dots at every kSpacing of the normalised plane (x, y in [-0.6, 0.6]).
constexpr double kSpacing = 0.1;
constexpr int kDots = 6;          // on each side of the centre
constexpr double kDotSigma = 1.2;  // [px of the input]

// The image the lens of `camera` sees of the dot grid: each pixel's ray (undistorted by the
// simulator's model) meets the grid's plane; 3 x 3 samples per pixel.
cv::Mat1f distortedDotGrid(const CameraParameters& camera) {
  const Intrinsics& k = camera.intrinsics;
  const double sigma = kDotSigma / k.fx;  // normalised
  cv::Mat1f image(k.height, k.width, 0.0f);
  for (int v = 0; v < k.height; ++v) {
    for (int u = 0; u < k.width; ++u) {
      double sum = 0.0;
      for (int j = 0; j < 3; ++j) {
        for (int i = 0; i < 3; ++i) {
          const cv::Point2d n = sim::undistortNormalised(
              camera.distortion, {(u + (i - 1) / 3.0 - k.cx) / k.fx, (v + (j - 1) / 3.0 - k.cy) / k.fy});
          const double dx = n.x - kSpacing * std::round(n.x / kSpacing);
          const double dy = n.y - kSpacing * std::round(n.y / kSpacing);
          sum += std::exp(-(dx * dx + dy * dy) / (2.0 * sigma * sigma));
        }
      }
      image(v, u) = static_cast<float>(sum / 9.0);
    }
  }
  return image;
}

// Intensity-weighted centre of the dot near `expected` (a window of +-4 px).
cv::Point2d dotCentre(const cv::Mat1f& image, cv::Point2d expected) {
  const int u0 = static_cast<int>(std::lround(expected.x)), v0 = static_cast<int>(std::lround(expected.y));
  double sum = 0.0, su = 0.0, sv = 0.0;
  for (int v = v0 - 4; v <= v0 + 4; ++v) {
    for (int u = u0 - 4; u <= u0 + 4; ++u) {
      if (u < 0 || v < 0 || u >= image.cols || v >= image.rows) continue;
      const double w = std::max(0.0f, image(v, u) - 0.05f);  // above the neighbours' tails
      sum += w;
      su += w * u;
      sv += w * v;
    }
  }
  return sum > 0.0 ? cv::Point2d(su / sum, sv / sum) : cv::Point2d(-1e9, -1e9);
}

struct DotCheck {
  int dots = 0;           // grid dots whose window lies inside the image
  double worst = 0.0;     // largest distance [px] between found and expected centre
};

// Finds every grid dot of `image` (of intrinsics k, a pinhole) where k says it is.
DotCheck checkDots(const cv::Mat1f& image, const Intrinsics& k) {
  DotCheck check;
  for (int j = -kDots; j <= kDots; ++j) {
    for (int i = -kDots; i <= kDots; ++i) {
      const cv::Point2d expected(k.cx + k.fx * kSpacing * i, k.cy + k.fy * kSpacing * j);
      if (expected.x < 6 || expected.y < 6 || expected.x > image.cols - 7 || expected.y > image.rows - 7) continue;
      const cv::Point2d found = dotCentre(image, expected);
      check.worst = std::max(check.worst, cv::norm(found - expected));
      ++check.dots;
    }
  }
  return check;
}

// Where the ray of output pixel (u, v) meets the input image (the test's own model), for an
// output camera of focal length f centred on the working frame.
cv::Point2d inputPixel(const Undistorter& undistorter, double f, cv::Point2d output) {
  const Intrinsics& out = undistorter.intrinsics();
  const CameraParameters& in = undistorter.inputCamera();
  const cv::Point2d d = sim::distortNormalised(in.distortion, {(output.x - out.cx) / f, (output.y - out.cy) / f});
  return {in.intrinsics.cx + in.intrinsics.fx * d.x, in.intrinsics.cy + in.intrinsics.fy * d.y};
}

// The largest excursion [px] beyond the input image of any working frame border pixel's source
// (negative: all inside), with the working frame's focal length scaled by `zoom`.
double borderExcursion(const Undistorter& undistorter, double zoom = 1.0) {
  const cv::Size input = undistorter.imageSize();
  const Intrinsics& out = undistorter.intrinsics();
  const double f = out.fx * zoom;
  double worst = -std::numeric_limits<double>::infinity();
  const auto visit = [&](double u, double v) {
    const cv::Point2d p = inputPixel(undistorter, f, {u, v});
    worst = std::max({worst, -p.x, -p.y, p.x - (input.width - 1), p.y - (input.height - 1)});
  };
  for (int u = 0; u < out.width; ++u) {
    visit(u, 0);
    visit(u, out.height - 1);
  }
  for (int v = 0; v < out.height; ++v) {
    visit(0, v);
    visit(out.width - 1, v);
  }
  return worst;
}

CameraParameters lens(double k1, double k2, double p1 = 0.0, double p2 = 0.0) {
  CameraParameters camera;
  // 4:3, principal point off the centre, fx != fy: the working frame squares and centres it.
  camera.intrinsics = {250.0, 252.0, 163.2, 117.4, 320, 240};
  camera.distortion.k1 = k1;
  camera.distortion.k2 = k2;
  camera.distortion.p1 = p1;
  camera.distortion.p2 = p2;
  return camera;
}

// The same lens on a sensor of `factor` times the resolution.
CameraParameters scaled(CameraParameters camera, double factor) {
  Intrinsics& k = camera.intrinsics;
  k = {k.fx * factor, k.fy * factor, (k.cx + 0.5) * factor - 0.5, (k.cy + 0.5) * factor - 0.5,
       static_cast<int>(k.width * factor), static_cast<int>(k.height * factor)};
  return camera;
}

void expectStraightGrid(const CameraParameters& camera, int working_size) {
  const cv::Size size(camera.intrinsics.width, camera.intrinsics.height);
  const Undistorter undistorter(camera, size, working_size);
  ASSERT_TRUE(undistorter.remaps());
  const cv::Mat1f distorted = distortedDotGrid(camera);
  const cv::Mat1f undistorted = undistorter.apply(distorted);
  ASSERT_EQ(undistorted.size(), cv::Size(working_size, working_size));
  const Intrinsics& out = undistorter.intrinsics();
  EXPECT_EQ(out.fx, out.fy);
  EXPECT_DOUBLE_EQ(out.cx, (working_size - 1) / 2.0);
  EXPECT_DOUBLE_EQ(out.cy, (working_size - 1) / 2.0);
  EXPECT_EQ(undistorter.workingFx(), out.fx);
  // Every dot where a pinhole of the reported intrinsics puts it: the rows and columns are
  // straight and evenly spaced again, at the reported focal length.
  const DotCheck after = checkDots(undistorted, out);
  EXPECT_GE(after.dots, 40);
  EXPECT_LT(after.worst, 0.15) << "undistorted dots off their pinhole positions";
  // The check can fail: in the distorted input, taken as a pinhole, the dots are pixels away.
  const DotCheck before = checkDots(distorted, undistorter.inputCamera().intrinsics);
  EXPECT_GT(before.worst, 2.0);
  // No pixel from outside the input, and (pincushion) not more zoom than that needs.
  EXPECT_LE(borderExcursion(undistorter), 1e-6);
}

TEST(Undistortion, BarrelLensGridComesOutStraightAtTheLensFocalLength) {
  const CameraParameters camera = lens(-0.25, 0.06, 0.001, -0.0015);
  expectStraightGrid(camera, 240);
  // A barrel lens fits at its own scale: the undistorted view is never made wider (which would
  // shrink and blur the centre).
  const Undistorter undistorter(camera, {320, 240}, 240);
  EXPECT_NEAR(undistorter.intrinsics().fx, std::sqrt(250.0 * 252.0), 1e-9);
}

// A frame larger than the working frame is shrunk (area) before the remap, a smaller one is
// enlarged by it: the dots land where the working frame's intrinsics say either way.
TEST(Undistortion, WorkingFramesOfOtherSizes) {
  const CameraParameters camera = scaled(lens(-0.25, 0.06, 0.001, -0.0015), 2.0);  // 640 x 480
  expectStraightGrid(camera, 240);
  EXPECT_NEAR(Undistorter(camera, {640, 480}, 240).workingFx(), std::sqrt(500.0 * 504.0) / 2.0, 1e-9);
  expectStraightGrid(lens(-0.25, 0.06), 288);
}

TEST(Undistortion, PincushionLensZoomsInJustEnoughToLeaveNoInvalidPixel) {
  const CameraParameters camera = lens(0.2, 0.05);
  expectStraightGrid(camera, 240);
  const Undistorter undistorter(camera, {320, 240}, 240);
  // At the lens's own scale the corners would come from outside the image (black corners).
  EXPECT_GT(undistorter.intrinsics().fx, std::sqrt(250.0 * 252.0) * 1.02);
  // The widest view that fits: 0.2 % wider and a border pixel would come from outside.
  EXPECT_GT(borderExcursion(undistorter, 0.998), 0.0);
}

TEST(Undistortion, RationalModel) {
  CameraParameters camera = lens(-0.3, 0.08);
  camera.distortion.k3 = -0.01;
  camera.distortion.k4 = 0.05;
  camera.distortion.k5 = -0.02;
  camera.distortion.k6 = 0.01;
  ASSERT_TRUE(camera.distortion.rational());
  ASSERT_EQ(camera.distortion.coefficients().size(), 8u);
  expectStraightGrid(camera, 240);
}

// Resampling blurs, and on a multi-depth scene blur shifts which layer dominates the correlation
// (the finest texture suffers first), which shows as scale drift: bilinear undistortion made a
// simulated circle drift far more than bicubic, which drifts like the pinhole flight. Fine texture
// must come through: bilinear keeps about 0.7 of its gradient energy here, bicubic over 0.9.
TEST(Undistortion, KeepsFineTexture) {
  CameraParameters camera;
  camera.intrinsics = {443.4, 443.4, 255.5, 255.5, 512, 512};
  camera.distortion.k1 = -0.2;
  camera.distortion.k2 = 0.05;
  cv::Mat1f texture(512, 512);
  cv::RNG rng(7);
  rng.fill(texture, cv::RNG::NORMAL, 0.0, 1.0);
  cv::GaussianBlur(texture, texture, cv::Size(), 0.8);
  const cv::Mat1f undistorted = Undistorter(camera, {512, 512}, 512).apply(texture);
  // Near the centre the lens hardly scales (magnification 1 .. 1.02): what is lost there is blur.
  const auto gradientEnergy = [](const cv::Mat1f& image) {
    const cv::Mat1f centre = image(cv::Rect(128, 128, 256, 256));
    cv::Mat1f dx, dy;
    cv::Sobel(centre, dx, CV_32F, 1, 0, 1);
    cv::Sobel(centre, dy, CV_32F, 0, 1, 1);
    return cv::mean(dx.mul(dx))[0] + cv::mean(dy.mul(dy))[0];
  };
  EXPECT_GT(gradientEnergy(undistorted) / gradientEnergy(texture), 0.85);
}

TEST(Undistortion, NoDistortionKeepsTheFrameAsItIs) {
  CameraParameters camera = lens(0.0, 0.0);
  const Undistorter undistorter(camera, {320, 240}, 512);
  EXPECT_FALSE(undistorter.remaps());
  const cv::Mat1b frame(240, 320, static_cast<unsigned char>(7));
  const cv::Mat out = undistorter.apply(frame);
  EXPECT_EQ(out.data, frame.data);  // not even copied
  EXPECT_EQ(undistorter.intrinsics().fx, 250.0);
  EXPECT_EQ(undistorter.intrinsics().cx, 163.2);
  EXPECT_TRUE(undistorter.notes().empty());
  EXPECT_DOUBLE_EQ(undistorter.workingFx(), 250.0 * 512 / 240);
}

// Any frame the core takes comes out as the grey float working frame toGreyFloat would make.
TEST(Undistortion, UndistortsEveryPixelTypeAndRefusesAnotherSize) {
  const Undistorter undistorter(lens(-0.2, 0.05), {320, 240}, 128);
  const std::pair<int, double> types[] = {{CV_8UC1, 100.0 / 255.0}, {CV_8UC3, 100.0 / 255.0},
                                          {CV_8UC4, 100.0 / 255.0}, {CV_16UC1, 100.0 / 65535.0},
                                          {CV_32FC1, 100.0}, {CV_64FC1, 100.0}};
  for (const auto& [type, value] : types) {
    const cv::Mat frame(240, 320, type, cv::Scalar::all(100));
    const cv::Mat out = undistorter.apply(frame);
    EXPECT_EQ(out.type(), CV_32FC1);
    EXPECT_EQ(out.size(), cv::Size(128, 128));
    // A uniform frame stays uniform: nothing from outside it, no border colour.
    double low = 0.0, high = 0.0;
    cv::minMaxLoc(out, &low, &high);
    EXPECT_NEAR(low, value, 1e-5 * value) << type;
    EXPECT_NEAR(high, value, 1e-5 * value) << type;
  }
  EXPECT_THROW(undistorter.apply(cv::Mat1b(240, 300)), InputError);
  // A frame too small to register stays refused, though its working frame would be large.
  const Undistorter tiny(scaled(lens(-0.2, 0.05), 0.125), {40, 30}, 128);
  EXPECT_THROW(tiny.apply(cv::Mat1b(30, 40, static_cast<unsigned char>(9))), InputError);
}

TEST(Undistortion, CalibrationOfAnotherResolutionIsMappedAndSaidSo) {
  // The o-eFMT authors' camera and their 512 x 512 images.
  CameraParameters camera;
  camera.intrinsics = {2955.7, 2949.9, 2023.1, 1510.7, 4056, 3040};
  camera.distortion.k1 = -0.1;
  const Undistorter undistorter(camera, {512, 512}, 512, "cam_param.yaml");
  const Intrinsics expected = intrinsicsForImageSize(camera.intrinsics, {512, 512});
  EXPECT_DOUBLE_EQ(undistorter.inputCamera().intrinsics.fx, expected.fx);
  EXPECT_DOUBLE_EQ(undistorter.inputCamera().intrinsics.cy, expected.cy);
  EXPECT_NEAR(undistorter.inputCamera().intrinsics.fx, 497.8, 0.05);
  const std::vector<std::string> notes = undistorter.notes();
  ASSERT_EQ(notes.size(), 2u);
  EXPECT_EQ(notes[0].rfind("cam_param.yaml describes a 4056x3040 camera; the 512x512 images are taken as "
                           "its centred 3040x3040 crop resized: fx 497.8 px", 0), 0u) << notes[0];
  EXPECT_NE(notes[1].find("undistorting (cam_param.yaml: k1 -0.1)"), std::string::npos) << notes[1];
  // Width and height 0: the calibration is taken to be the images' own.
  camera.intrinsics = {400.0, 400.0, 255.5, 255.5, 0, 0};
  EXPECT_EQ(describeSizeMapping(camera.intrinsics, {512, 512}, "camera_info"), "");
  EXPECT_DOUBLE_EQ(Undistorter(camera, {512, 512}, 512).inputCamera().intrinsics.fx, 400.0);
}

// Unusable calibrations: one line naming the source and what is wrong, never a crash or a
// frame of garbage.
TEST(Undistortion, RefusesUnusableDistortionInOneLine) {
  const auto message = [](const CameraParameters& camera) -> std::string {
    try {
      Undistorter undistorter(camera, {320, 240}, 240, "camera_info");
    } catch (const InputError& e) {
      return e.what();
    }
    return "";
  };
  const auto expectRefused = [&](const CameraParameters& camera, const std::string& part) {
    const std::string text = message(camera);
    EXPECT_EQ(text.rfind("camera_info: ", 0), 0u) << text;
    EXPECT_NE(text.find(part), std::string::npos) << text;
    EXPECT_EQ(text.find('\n'), std::string::npos) << text;
  };
  expectRefused(lens(std::numeric_limits<double>::quiet_NaN(), 0.0), "coefficient k1 is not finite");
  expectRefused(lens(0.0, std::numeric_limits<double>::infinity()), "coefficient k2 is not finite");
  // Folds over inside the view (r (1 - 5 r^2) turns back at r = 0.26): not invertible.
  expectRefused(lens(-5.0, 0.0), "cannot be undone");
  // Absurdly strong: nothing but a sliver of the centre maps inside the image.
  expectRefused(lens(1e6, 0.0), "cannot be undone");
  expectRefused(lens(0.0, 0.0, 1e3, 0.0), "cannot be undone");
  CameraParameters outside = lens(-0.1, 0.0);
  outside.intrinsics.cx = -40.0;
  expectRefused(outside, "principal point");
  CameraParameters nan_focal = lens(-0.1, 0.0);
  nan_focal.intrinsics.fx = std::numeric_limits<double>::quiet_NaN();
  expectRefused(nan_focal, "not finite");
}

TEST(Undistortion, SameCameraComparesEveryField) {
  const CameraParameters a = lens(-0.2, 0.05);
  CameraParameters b = a;
  EXPECT_TRUE(sameCamera(a, b));
  b.distortion.k6 = 1e-9;
  EXPECT_FALSE(sameCamera(a, b));
  b = a;
  b.intrinsics.width = 321;
  EXPECT_FALSE(sameCamera(a, b));
  const Undistorter undistorter(a, {320, 240}, 240);
  EXPECT_TRUE(undistorter.madeFor(a, {320, 240}));
  EXPECT_FALSE(undistorter.madeFor(a, {320, 241}));
}

}  // namespace
}  // namespace oefmt
