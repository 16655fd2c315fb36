// SPDX-License-Identifier: GPL-3.0-or-later
// The authors' folder layout: reading it as their users have it, errors, and the simulator's
// writer round trip.
#include <gtest/gtest.h>

#include <fstream>
#include <functional>
#include <iterator>

#include <opencv2/imgcodecs.hpp>

#include "support/temp_dir.h"
#include "oefmt/io/dataset.h"
#include "oefmt/error.h"
#include "oefmt/evaluation/evaluation.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/folder_writer.h"

namespace oefmt {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

// cam_param.yaml exactly as the authors ship it: 4056 x 3040 camera, no final newline.
const char* const kAuthorsCamParam =
    "%YAML:1.0\n\nCamera.type: \"PinHole\"\n\nCamera.fx: 2955.7\nCamera.fy: 2949.9\n"
    "Camera.cx: 2023.1\nCamera.cy: 1510.7\n\nCamera.k1: 0.1601\nCamera.k2: -0.3277\n"
    "Camera.p1: -0.00073991\nCamera.p2: 0.0051\n\nCamera.width: 4056\nCamera.height: 3040";

void writeText(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary);
  out << text;
}

cv::Mat testImage(int seed, int size = 64) {
  cv::Mat3b image(size, size);
  cv::RNG random(static_cast<std::uint64_t>(seed));
  random.fill(image, cv::RNG::UNIFORM, cv::Scalar::all(0), cv::Scalar::all(256));
  return image;
}

// A folder like the authors': n images 0001.png..., a list (CRLF, no final newline), cam_param.
void writeAuthorsFolder(const TempDir& dir, int n) {
  fs::create_directories(dir.path() / "Images");
  std::string list;
  for (int k = 1; k <= n; ++k) {
    char name[16];
    std::snprintf(name, sizeof(name), "%04d.png", k);
    cv::imwrite((dir.path() / "Images" / name).string(), testImage(k));
    list += std::string(k > 1 ? "\r\n" : "") + name;
  }
  writeText(dir / "imageList.txt", list);
  writeText(dir / "cam_param.yaml", kAuthorsCamParam);
}

TEST(Dataset, ReadsTheAuthorsLayoutAndScalesTheirIntrinsics) {
  TempDir dir;
  writeAuthorsFolder(dir, 3);
  // The authors' timestamps.txt: calendar stamps copied from another flight, more than images.
  std::string stamps;
  for (int k = 0; k < 5; ++k) stamps += "2020121715432" + std::to_string(2 * k) + "\n";
  writeText(dir / "timestamps.txt", stamps);

  const FolderDataset dataset(dir.path().string());
  ASSERT_EQ(dataset.size(), 3u);  // the last line without newline counts
  EXPECT_EQ(dataset.imageName(2), "0003.png");
  EXPECT_EQ(dataset.imageSize(), cv::Size(64, 64));
  EXPECT_FALSE(dataset.hasTimestamps());
  EXPECT_EQ(dataset.timestamp(2), 2.0);
  ASSERT_EQ(dataset.warnings().size(), 1u);
  EXPECT_NE(dataset.warnings()[0].find("5 stamps for 3 images"), std::string::npos);

  // A centred 3040 x 3040 crop of the 4056 x 3040 camera, resized to 64 x 64.
  const double k = 64.0 / 3040.0;
  const Intrinsics& in = dataset.intrinsics();
  EXPECT_NEAR(in.fx, 2955.7 * k, 1e-9);
  EXPECT_NEAR(in.fy, 2949.9 * k, 1e-9);
  EXPECT_NEAR(in.cx, (2023.1 - 508.0 + 0.5) * k - 0.5, 1e-9);
  EXPECT_NEAR(in.cy, (1510.7 + 0.5) * k - 0.5, 1e-9);
  EXPECT_EQ(in.width, 64);
  EXPECT_EQ(dataset.fileIntrinsics().width, 4056);
  EXPECT_DOUBLE_EQ(dataset.distortion().k2, -0.3277);
  EXPECT_DOUBLE_EQ(dataset.distortion().p1, -0.00073991);

  const cv::Mat image = dataset.loadImage(1);
  EXPECT_EQ(cv::norm(image, testImage(2), cv::NORM_INF), 0.0);
}

TEST(Dataset, UsesMatchingTimestampsInBothFormats) {
  TempDir dir;
  writeAuthorsFolder(dir, 3);
  writeText(dir / "timestamps.txt", "20201217154322\n20201217154324\n20201217154326");
  FolderDataset calendar(dir.path().string());
  ASSERT_TRUE(calendar.hasTimestamps());
  EXPECT_DOUBLE_EQ(calendar.timestamp(0), 1608219802.0);  // 2020-12-17 15:43:22 UTC
  EXPECT_DOUBLE_EQ(calendar.timestamp(2) - calendar.timestamp(0), 4.0);

  writeText(dir / "timestamps.txt", "1.0\n1.25\n1.5\n");
  EXPECT_DOUBLE_EQ(FolderDataset(dir.path().string()).timestamp(1), 1.25);

  writeText(dir / "timestamps.txt", "1.0\n0.5\n1.5\n");  // not increasing: ignored
  const FolderDataset backwards(dir.path().string());
  EXPECT_FALSE(backwards.hasTimestamps());
  EXPECT_EQ(backwards.warnings().size(), 1u);
}

TEST(Dataset, WithoutListOrCameraSizeFallsBackSensibly) {
  TempDir dir;
  writeAuthorsFolder(dir, 2);
  fs::remove(dir.path() / "imageList.txt");
  writeText(dir / "cam_param.yaml", "Camera.fx: 50\nCamera.fy: 50\nCamera.cx: 31.5\nCamera.cy: 31.5");
  const FolderDataset dataset(dir.path().string());
  EXPECT_EQ(dataset.size(), 2u);
  EXPECT_EQ(dataset.imageName(0), "0001.png");
  EXPECT_EQ(dataset.intrinsics().fx, 50.0);  // no Camera.width: the images are the camera's
  EXPECT_EQ(dataset.intrinsics().width, 64);
  EXPECT_EQ(dataset.warnings().size(), 2u);
}

void expectDatasetError(const std::function<void()>& action, const std::string& fragment) {
  try {
    action();
    ADD_FAILURE() << "no DatasetError";
  } catch (const DatasetError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(Dataset, ClearErrorsForMissingOrBrokenFiles) {
  TempDir dir;
  expectDatasetError([&] { FolderDataset(dir / "nowhere"); }, "nowhere");
  writeAuthorsFolder(dir, 3);
  fs::remove(dir.path() / "Images" / "0002.png");
  writeText((dir.path() / "Images" / "0003.png").string(), "not a png");
  const FolderDataset dataset(dir.path().string());
  expectDatasetError([&] { dataset.loadImage(1); }, "0002.png' does not exist");
  // Reading ahead is only advice: a missing file or an index past the end says nothing (loading
  // it does).
  EXPECT_NO_THROW(dataset.adviseReading(1));
  EXPECT_NO_THROW(dataset.adviseReading(99));
  expectDatasetError([&] { dataset.loadImage(2); }, "cannot read image");
  EXPECT_THROW(dataset.loadImage(3), InputError);

  cv::imwrite((dir.path() / "Images" / "0002.png").string(), testImage(2, 32));
  expectDatasetError([&] { dataset.loadImage(1); }, "32x32");

  fs::remove(dir.path() / "cam_param.yaml");
  expectDatasetError([&] { FolderDataset(dir.path().string()); }, "cam_param.yaml");
  writeText(dir / "cam_param.yaml", "Camera.fy: 1\nCamera.cx: 1\nCamera.cy: 1\n");
  expectDatasetError([&] { FolderDataset(dir.path().string()); }, "Camera.fx");
  writeText(dir / "cam_param.yaml", "Camera.fx: [1, \n");
  // yaml-cpp finds the open bracket unclosed at the end of the text.
  expectDatasetError([&] { FolderDataset(dir.path().string()); }, "cam_param.yaml', line 2: end of sequence");
  writeText(dir / "cam_param.yaml", "Camera.fx: 400px\nCamera.fy: 1\nCamera.cx: 1\nCamera.cy: 1\n");
  expectDatasetError([&] { FolderDataset(dir.path().string()); }, "Camera.fx is not a number");
  writeText(dir / "cam_param.yaml", "Camera.fx: 1e400\nCamera.fy: 1\nCamera.cx: 1\nCamera.cy: 1\n");
  expectDatasetError([&] { FolderDataset(dir.path().string()); }, "Camera.fx is not finite");
}

TEST(Dataset, CameraParametersRoundTrip) {
  TempDir dir;
  CameraParameters camera;
  camera.intrinsics = {400.25, 401.5, 255.5, 250.125, 512, 500};
  camera.distortion = {-0.1, 0.02, 0.001, -0.002};
  writeCameraParameters(dir / "cam.yaml", camera);
  const CameraParameters read = readCameraParameters(dir / "cam.yaml");
  EXPECT_EQ(read.intrinsics.fx, 400.25);
  EXPECT_EQ(read.intrinsics.cy, 250.125);
  EXPECT_EQ(read.intrinsics.height, 500);
  EXPECT_EQ(read.distortion.k2, 0.02);
  EXPECT_EQ(read.distortion.p2, -0.002);
}

// k3 (ORB-SLAM-style files) and the rational k4..k6 are read and written; the authors' ten keys
// stay the only ones when those are zero; Camera.type other than PinHole is refused by name.
TEST(Dataset, CameraParametersHigherOrderDistortionAndType) {
  TempDir dir;
  CameraParameters camera;
  camera.intrinsics = {400.25, 401.5, 255.5, 250.125, 512, 500};
  camera.distortion.k1 = -0.3;
  writeCameraParameters(dir / "plain.yaml", camera);
  std::ifstream plain(dir / "plain.yaml");
  const std::string plain_text((std::istreambuf_iterator<char>(plain)), std::istreambuf_iterator<char>());
  EXPECT_EQ(plain_text.find("Camera.k3"), std::string::npos);
  EXPECT_NE(plain_text.find("Camera.p2"), std::string::npos);
  camera.distortion.k3 = 0.01;
  camera.distortion.k4 = 0.2;
  camera.distortion.k6 = -0.05;
  writeCameraParameters(dir / "cam.yaml", camera);
  const CameraParameters read = readCameraParameters(dir / "cam.yaml");
  EXPECT_EQ(read.distortion.k3, 0.01);
  EXPECT_EQ(read.distortion.k4, 0.2);
  EXPECT_EQ(read.distortion.k5, 0.0);
  EXPECT_EQ(read.distortion.k6, -0.05);
  EXPECT_TRUE(read.distortion.rational());
  EXPECT_EQ(read.distortion.text(), "k1 -0.3 k3 0.01 k4 0.2 k6 -0.05");
  writeText(dir / "fisheye.yaml", "Camera.type: \"KannalaBrandt8\"\nCamera.fx: 1\nCamera.fy: 1\nCamera.cx: 1\nCamera.cy: 1\n");
  expectDatasetError([&] { readCameraParameters(dir / "fisheye.yaml"); }, "Camera.type 'KannalaBrandt8' is not supported");
  writeText(dir / "pinhole.yaml", "Camera.type: pinhole\nCamera.fx: 1\nCamera.fy: 1\nCamera.cx: 1\nCamera.cy: 1\n");
  EXPECT_FALSE(readCameraParameters(dir / "pinhole.yaml").distortion.any());
}

TEST(Dataset, IntrinsicsForImageSize) {
  const Intrinsics camera{1000.0, 1000.0, 999.5, 499.5, 2000, 1000};
  const Intrinsics half = intrinsicsForImageSize(camera, {1000, 500});  // same aspect: resize
  EXPECT_DOUBLE_EQ(half.fx, 500.0);
  EXPECT_DOUBLE_EQ(half.cx, 499.5);
  EXPECT_DOUBLE_EQ(half.cy, 249.5);
  const Intrinsics square = intrinsicsForImageSize(camera, {500, 500});  // crop 1000 x 1000
  EXPECT_DOUBLE_EQ(square.fx, 500.0);
  EXPECT_DOUBLE_EQ(square.cx, 249.5);
  EXPECT_THROW(intrinsicsForImageSize(Intrinsics{}, {10, 10}), InputError);
}

TEST(Dataset, ParsesTimestamps) {
  double t = 0.0;
  EXPECT_TRUE(parseTimestamp("20201217154322", t));
  EXPECT_DOUBLE_EQ(t, 1608219802.0);
  EXPECT_TRUE(parseTimestamp(" 12.5\r", t));
  EXPECT_DOUBLE_EQ(t, 12.5);
  EXPECT_FALSE(parseTimestamp("12.5 s", t));
  EXPECT_FALSE(parseTimestamp("", t));
  EXPECT_FALSE(parseTimestamp("20201317154322", t));  // month 13
}

TEST(Dataset, SimulatedFlightRoundTrip) {
  TempDir dir;
  sim::FlightOptions options;
  options.width = options.height = 96;
  options.track.frames = 4;
  options.track.length = 12.0;
  options.distortion.k1 = -0.05;
  const sim::FlightPlan plan = sim::planFlight(options);
  std::vector<cv::Mat1b> images;
  {
    sim::FolderFlightWriter writer(dir.path().string(), plan.camera, 4, sim::groundTruthHeader(plan));
    sim::renderFlight(plan, [&](int k, const cv::Mat1b& image, const cv::Mat1b&) {
      writer.write(image, plan.poses[k], plan.stamps[k]);
      images.push_back(image.clone());
    });
    writer.finish();
  }
  const FolderDataset dataset(dir.path().string());
  ASSERT_EQ(dataset.size(), 4u);
  EXPECT_TRUE(dataset.warnings().empty());
  EXPECT_TRUE(dataset.hasTimestamps());
  EXPECT_EQ(dataset.imageName(3), "0004.png");
  EXPECT_NEAR(dataset.intrinsics().fx, plan.camera.intrinsics.fx, 1e-6);
  EXPECT_NEAR(dataset.intrinsics().cx, plan.camera.intrinsics.cx, 1e-6);
  EXPECT_DOUBLE_EQ(dataset.distortion().k1, -0.05);
  const StampedTrajectory truth = readTum(dir / "groundtruth.tum");
  ASSERT_EQ(truth.size(), 4u);
  for (std::size_t k = 0; k < 4; ++k) {
    EXPECT_NEAR(dataset.timestamp(k), plan.stamps[k], 1e-6);
    EXPECT_NEAR(truth[k].stamp, plan.stamps[k], 1e-6);
    EXPECT_NEAR(truth[k].position.x(), plan.poses[k].position[0], 1e-6);
    EXPECT_NEAR(truth[k].position.z(), plan.poses[k].position[2], 1e-6);
    EXPECT_EQ(cv::norm(dataset.loadImage(k), images[k], cv::NORM_INF), 0.0);
  }
}

}  // namespace
}  // namespace oefmt
