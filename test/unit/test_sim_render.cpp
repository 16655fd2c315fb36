// SPDX-License-Identifier: GPL-3.0-or-later
// The renderer agrees with its ground truth: plane homographies between frames, image axes,
// lens distortion, determinism and the simulated sensor.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "support/temp_dir.h"
#include "oefmt/io/dataset.h"
#include "oefmt/error.h"

#include "oefmt/sim/flight.h"
#include "oefmt/sim/renderer.h"
#include "oefmt/sim/texture.h"

namespace oefmt {
namespace sim {
namespace {

// A small flight along a circle with the heading following the track, so consecutive frames
// differ by a shift, a rotation and (with climb) a zoom.
FlightOptions smallFlight() {
  FlightOptions options;
  options.width = options.height = 192;
  options.track.frames = 6;
  options.track.length = 60.0;
  options.track.heading = HeadingMode::kTrack;
  options.track.climb = 1.5;
  options.seed = 5;
  return options;
}

// The camera matrix and world-to-image projection of the documented convention, written out
// independently of the renderer: optical axes x = R_z(yaw) e_x, y = -(R_z(yaw) e_y), z = -e_z.
cv::Matx33d cameraMatrix(const Intrinsics& k) { return {k.fx, 0, k.cx, 0, k.fy, k.cy, 0, 0, 1}; }

// Homography from world x-y on the plane z = h to pixels.
cv::Matx33d planeToImage(const CameraParameters& camera, const FlightPose& pose, double h) {
  const double c = std::cos(pose.yaw), s = std::sin(pose.yaw);
  const cv::Matx33d world_to_optical(c, s, 0, s, -c, 0, 0, 0, -1);  // rows: optical axes in world
  const cv::Vec3d offset = world_to_optical * (cv::Vec3d(0, 0, h) - pose.position);
  const cv::Matx33d columns(world_to_optical(0, 0), world_to_optical(0, 1), offset[0],
                            world_to_optical(1, 0), world_to_optical(1, 1), offset[1],
                            world_to_optical(2, 0), world_to_optical(2, 1), offset[2]);
  return cameraMatrix(camera.intrinsics) * columns;
}

struct LayerComparison {
  double mean_error = 0.0;
  int pixels = 0;
};

// Warps `older` into `newer`'s view through the plane z = h and compares the pixels where both
// frames see `layer` (away from its edges).
LayerComparison compareThroughPlane(const RenderedFrame& older, const FlightPose& older_pose,
                                    const RenderedFrame& newer, const FlightPose& newer_pose,
                                    const CameraParameters& camera, double h, int layer) {
  const cv::Matx33d newer_to_older = planeToImage(camera, older_pose, h) * planeToImage(camera, newer_pose, h).inv();
  cv::Mat1f warped;
  cv::Mat1b warped_layers;
  const cv::Size size = newer.image.size();
  cv::warpPerspective(older.image, warped, newer_to_older, size, cv::INTER_LINEAR | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT, cv::Scalar(-1));
  cv::warpPerspective(older.layers, warped_layers, newer_to_older, size, cv::INTER_NEAREST | cv::WARP_INVERSE_MAP,
                      cv::BORDER_CONSTANT, cv::Scalar(RenderedFrame::kMixedLayers));
  // Only pixels whose whole neighbourhood sees the layer in both frames (bilinear footprint).
  cv::Mat1b mask = (newer.layers == layer) & (warped_layers == layer) & (warped >= 0.0f);
  cv::erode(mask, mask, cv::Mat(), cv::Point(-1, -1), 2);
  LayerComparison result;
  double sum = 0.0;
  for (int r = 0; r < size.height; ++r) {
    for (int c = 0; c < size.width; ++c) {
      if (!mask(r, c)) continue;
      sum += std::fabs(warped(r, c) - newer.image(r, c));
      ++result.pixels;
    }
  }
  result.mean_error = result.pixels > 0 ? sum / result.pixels : 1.0;
  return result;
}

TEST(SimRender, EachFlatLayerMovesWithItsPlaneHomography) {
  const FlightPlan plan = planFlight(smallFlight());
  const auto scene = std::make_shared<const Scene>(plan.scene);
  const Renderer renderer(scene, plan.camera, plan.supersample);
  const double heights[] = {0.0, plan.scene.levels[0].height};  // ground and the flat level
  int checked[2] = {0, 0};
  for (std::size_t k = 0; k + 1 < plan.poses.size(); ++k) {
    const RenderedFrame a = renderer.render(plan.poses[k]);
    const RenderedFrame b = renderer.render(plan.poses[k + 1]);
    for (int layer = 0; layer < 2; ++layer) {
      const LayerComparison right =
          compareThroughPlane(a, plan.poses[k], b, plan.poses[k + 1], plan.camera, heights[layer], layer);
      const LayerComparison wrong =
          compareThroughPlane(a, plan.poses[k], b, plan.poses[k + 1], plan.camera, heights[1 - layer], layer);
      if (right.pixels < 300) continue;  // this layer is barely in view in both frames
      ++checked[layer];
      EXPECT_LT(right.mean_error, 0.02) << "frame " << k << " layer " << layer << " (" << right.pixels << " px)";
      EXPECT_GT(wrong.mean_error, 3.0 * right.mean_error) << "frame " << k << " layer " << layer;
    }
  }
  EXPECT_GE(checked[0], 4);
  EXPECT_GE(checked[1], 1);
}

TEST(SimRender, SeveralDepthsAreInView) {
  const FlightPlan plan = planFlight(smallFlight());
  const Renderer renderer(std::make_shared<const Scene>(plan.scene), plan.camera, 1);
  const RenderedFrame frame = renderer.render(plan.poses[0]);
  int counts[3] = {0, 0, 0};
  for (unsigned char layer : cv::Mat_<unsigned char>(frame.layers)) {
    if (layer < 3) ++counts[layer];
  }
  const double total = static_cast<double>(frame.layers.total());
  EXPECT_GT(counts[0] / total, 0.3);
  EXPECT_GT((counts[1] + counts[2]) / total, 0.05);
}

// --raised and --fill: nearly all terraces raised and filled, the roofs take most of the view;
// shares beyond 1 are refused.
TEST(SimRender, RaisedShareAndFillSetTheRoofsArea) {
  FlightOptions options = smallFlight();
  options.raised_share = 1.0;
  options.fill = 0.95;
  const FlightPlan plan = planFlight(options);
  const Renderer renderer(std::make_shared<const Scene>(plan.scene), plan.camera, 1);
  const cv::Mat1b layers = renderer.render(plan.poses[0]).layers;
  const double ground = static_cast<double>(cv::countNonZero(layers == 0)) / layers.total();
  EXPECT_LT(ground, 0.5);
  EXPECT_GT(ground, 0.1);  // the gaps between the tops stay in view
  options.raised_share = 1.5;
  EXPECT_THROW(planFlight(options), InputError);
  options.raised_share = 0.7;
  options.fill = -0.1;
  EXPECT_THROW(planFlight(options), InputError);
}

TEST(SimRender, FlatLevelPixelsLieOnThatLevelsTops) {
  const FlightPlan plan = planFlight(smallFlight());
  const Scene scene(plan.scene);
  const Renderer renderer(std::make_shared<const Scene>(plan.scene), plan.camera, 1);
  const double level_height = plan.scene.levels[0].height;
  const RenderedFrame frame = renderer.render(plan.poses[2]);
  int checked = 0;
  for (int v = 0; v < frame.layers.rows; ++v) {
    for (int u = 0; u < frame.layers.cols; ++u) {
      if (frame.layers(v, u) != 1) continue;
      // Where this pixel's ray crosses the level's plane there must be a top of that level.
      const cv::Point2d xy = pixelOnPlane(plan.camera, plan.poses[2], cv::Point2d(u, v), level_height);
      double height = -1.0;
      ASSERT_EQ(scene.layerAt(xy.x, xy.y, &height), 1) << u << ", " << v;
      EXPECT_DOUBLE_EQ(height, level_height);
      ++checked;
    }
  }
  EXPECT_GT(checked, 100);
}

// A scene with only the ground, for checks of the image axes.
std::shared_ptr<const Scene> groundOnlyScene() {
  SceneConfig config;
  config.levels.clear();
  config.texel = 0.035;  // about half a pixel at the tests' 10 m and fx 150-160: no aliasing
  config.texture_size = 1024;
  config.feature_texels = 40.0;
  return std::make_shared<const Scene>(config);
}

TEST(SimRender, ImageAxesFollowTheWorldConvention) {
  CameraParameters camera;
  camera.intrinsics = {160.0, 160.0, 79.5, 79.5, 160, 160};
  const Renderer renderer(groundOnlyScene(), camera, 2);
  FlightPose start;
  start.position = {0.0, 0.0, 10.0};
  FlightPose east = start, north = start;
  east.position[0] += 0.5;  // 8 px at 160 px per 10 m
  north.position[1] += 0.5;
  const cv::Mat1f a = renderer.render(start).image;
  const cv::Point2d east_shift = cv::phaseCorrelate(a, renderer.render(east).image);
  const cv::Point2d north_shift = cv::phaseCorrelate(a, renderer.render(north).image);
  // Moving east, the ground slides left (image right = east); moving north it slides down.
  EXPECT_NEAR(east_shift.x, -8.0, 0.2);
  EXPECT_NEAR(east_shift.y, 0.0, 0.2);
  EXPECT_NEAR(north_shift.x, 0.0, 0.2);
  EXPECT_NEAR(north_shift.y, 8.0, 0.2);
}

TEST(SimRender, LensDistortionMatchesTheRadialModel) {
  CameraParameters pinhole;
  pinhole.intrinsics = {150.0, 150.0, 79.5, 79.5, 160, 160};
  CameraParameters lens = pinhole;
  lens.distortion.k1 = -0.15;
  lens.distortion.k2 = 0.04;
  const auto scene = groundOnlyScene();
  FlightPose pose;
  pose.position = {1.0, 2.0, 10.0};
  const cv::Mat1f ideal = Renderer(scene, pinhole, 2).render(pose).image;
  const cv::Mat1f distorted = Renderer(scene, lens, 2).render(pose).image;
  // Pixel q of the ideal image appears in the distorted one at K * distort(K^-1 q).
  const Intrinsics& k = pinhole.intrinsics;
  cv::Mat1f map_x(ideal.size()), map_y(ideal.size());
  for (int v = 0; v < ideal.rows; ++v) {
    for (int u = 0; u < ideal.cols; ++u) {
      const double x = (u - k.cx) / k.fx, y = (v - k.cy) / k.fy;
      const double r2 = x * x + y * y;
      const double radial = 1.0 + lens.distortion.k1 * r2 + lens.distortion.k2 * r2 * r2;
      map_x(v, u) = static_cast<float>(k.fx * x * radial + k.cx);
      map_y(v, u) = static_cast<float>(k.fy * y * radial + k.cy);
    }
  }
  cv::Mat1f undistorted;
  cv::remap(distorted, undistorted, map_x, map_y, cv::INTER_LINEAR);
  const cv::Rect inner(16, 16, 128, 128);
  const double error = cv::mean(cv::abs(undistorted(inner) - ideal(inner)))[0];
  const double difference = cv::mean(cv::abs(distorted(inner) - ideal(inner)))[0];
  EXPECT_LT(error, 0.015);
  EXPECT_GT(difference, 4.0 * error);  // the distortion is visible, and undone by the model
}

TEST(SimRender, SameSeedSameImagesAndTablesDoNotChangeThem) {
  FlightOptions options = smallFlight();
  options.track.frames = 2;
  const FlightPlan plan = planFlight(options);
  std::vector<cv::Mat1b> first, second;
  renderFlight(plan, [&](int, const cv::Mat1b& image, const cv::Mat1b&) { first.push_back(image.clone()); });
  renderFlight(plan, [&](int, const cv::Mat1b& image, const cv::Mat1b&) { second.push_back(image.clone()); });
  ASSERT_EQ(first.size(), 2u);
  for (std::size_t k = 0; k < first.size(); ++k) EXPECT_EQ(cv::norm(first[k], second[k], cv::NORM_INF), 0.0);

  // The block layout computed on the fly equals the tabulated one.
  SceneConfig untabulated = plan.scene;
  untabulated.region = cv::Rect2d();
  const cv::Mat1f tabulated_image =
      Renderer(std::make_shared<const Scene>(plan.scene), plan.camera, 1).render(plan.poses[1]).image;
  const cv::Mat1f untabulated_image =
      Renderer(std::make_shared<const Scene>(untabulated), plan.camera, 1).render(plan.poses[1]).image;
  EXPECT_EQ(cv::norm(tabulated_image, untabulated_image, cv::NORM_INF), 0.0);

  options.seed = 6;
  std::vector<cv::Mat1b> other;
  renderFlight(planFlight(options), [&](int, const cv::Mat1b& image, const cv::Mat1b&) { other.push_back(image.clone()); });
  EXPECT_GT(cv::norm(first[0], other[0], cv::NORM_L1) / first[0].total(), 10.0);
}

TEST(SimSensor, NoiseAndBrightnessAsRequested) {
  const cv::Mat1f grey(200, 200, 0.5f);
  SensorOptions sensor;
  sensor.noise = 0.02;
  const cv::Mat1b noisy = sensorImage(grey, sensor, 1, 0);
  cv::Scalar mean, stddev;
  cv::meanStdDev(noisy, mean, stddev);
  EXPECT_NEAR(stddev[0] / 255.0, 0.02, 0.002);
  EXPECT_EQ(cv::norm(noisy, sensorImage(grey, sensor, 1, 0), cv::NORM_INF), 0.0);  // deterministic
  EXPECT_GT(cv::norm(noisy, sensorImage(grey, sensor, 1, 1), cv::NORM_INF), 0.0);  // per frame

  sensor.noise = 0.0;
  sensor.brightness = 0.2;
  sensor.brightness_period = 40.0;
  EXPECT_NEAR(cv::mean(sensorImage(grey, sensor, 1, 10))[0], 255.0 * 0.5 * 1.2, 0.6);
  EXPECT_NEAR(cv::mean(sensorImage(grey, sensor, 1, 30))[0], 255.0 * 0.5 * 0.8, 0.6);
}

TEST(SimTexture, ImageFilesServeAsLayerTextures) {
  test::TempDir dir;
  cv::Mat1b stripes(200, 200);
  for (int r = 0; r < stripes.rows; ++r) stripes.row(r).setTo(r % 20 < 10 ? 40 : 220);  // rows: north-south
  cv::imwrite(dir / "stripes.png", stripes);
  SceneConfig config;
  config.levels.clear();
  config.texel = 0.05;
  config.texture_files = {dir / "stripes.png"};
  const Scene scene(config);
  ASSERT_EQ(scene.texture(0).rows, 175);  // made tileable: the margin is folded in
  // Constant along x (east), alternating along y: the file's rows run south (samples away
  // from the cross-faded margin of 25 texels).
  EXPECT_FLOAT_EQ(scene.sample(0, 2.0, -1.76), scene.sample(0, 3.0, -1.76));
  EXPECT_GT(std::fabs(scene.sample(0, 2.0, -1.76) - scene.sample(0, 2.0, -2.26)), 0.5f);
  config.texture_files = {dir / "missing.png"};
  EXPECT_THROW(Scene{config}, DatasetError);
}

// The same seed gives the same texture with every compiler. Sums recorded with g++ 12; the
// sanitizer build (clang++ 14) runs this test too. Before the cells' centre took its two random
// draws in separate statements, clang++ drew them in the other order (a call's arguments are
// evaluated in an unspecified order) and rendered other ground textures than g++.
TEST(SimTexture, SameSeedSameTextureWithEveryCompiler) {
  EXPECT_NEAR(cv::sum(tileableTexture(256, 7, TextureStyle::kCells, 24.0))[0], 29072.851078, 1e-3);
  EXPECT_NEAR(cv::sum(tileableTexture(256, 7, TextureStyle::kStripes, 24.0))[0], 29393.705853, 1e-3);
  EXPECT_NEAR(cv::sum(tileableTexture(256, 7, TextureStyle::kNoise, 24.0))[0], 27785.456113, 1e-3);
}

TEST(SimTexture, TileableTexturesHaveNoSeam) {
  const cv::Mat1f tile = tileableTexture(256, 3, TextureStyle::kCells, 24.0);
  ASSERT_EQ(tile.rows, 256);
  // Across the wrap the texture changes no more than between neighbours inside it.
  double inside = 0.0, across = 0.0;
  for (int r = 0; r < tile.rows; ++r) {
    inside += std::fabs(tile(r, 128) - tile(r, 127));
    across += std::fabs(tile(r, 0) - tile(r, 255));
  }
  EXPECT_LT(across, 2.0 * inside);
}

}  // namespace
}  // namespace sim
}  // namespace oefmt
