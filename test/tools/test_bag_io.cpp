// SPDX-License-Identifier: GPL-3.0-or-later
// Bag I/O: folder -> bag -> frames identical, every supported encoding, clear errors.
#include <gtest/gtest.h>

#include <cmath>

#include <fstream>
#include <functional>
#include <map>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <rosbag/bag.h>

#include "support/temp_dir.h"
#include "oefmt/estimation/attitude.h"
#include "oefmt/io/dataset.h"
#include "oefmt/ros/bag_io.h"
#include "oefmt/ros/vehicle_messages.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/folder_writer.h"

namespace oefmt {
namespace {

using test::TempDir;

// Renders a small flight into `directory` in the authors' layout.
sim::FlightPlan writeSmallFlight(const std::string& directory, int frames = 5) {
  sim::FlightOptions options;
  options.width = options.height = 96;
  options.track.frames = frames;
  options.track.length = 15.0;
  options.distortion.k1 = 0.03;
  const sim::FlightPlan plan = sim::planFlight(options);
  sim::FolderFlightWriter writer(directory, plan.camera, frames, sim::groundTruthHeader(plan));
  sim::renderFlight(plan, [&](int k, const cv::Mat1b& image, const cv::Mat1b&) {
    writer.write(image, plan.poses[k], plan.stamps[k]);
  });
  writer.finish();
  return plan;
}

void expectSameCamera(const CameraParameters& a, const CameraParameters& b) {
  EXPECT_NEAR(a.intrinsics.fx, b.intrinsics.fx, 1e-6);
  EXPECT_NEAR(a.intrinsics.fy, b.intrinsics.fy, 1e-6);
  EXPECT_NEAR(a.intrinsics.cx, b.intrinsics.cx, 1e-6);
  EXPECT_NEAR(a.intrinsics.cy, b.intrinsics.cy, 1e-6);
  EXPECT_EQ(a.intrinsics.width, b.intrinsics.width);
  EXPECT_EQ(a.intrinsics.height, b.intrinsics.height);
  EXPECT_NEAR(a.distortion.k1, b.distortion.k1, 1e-12);
  EXPECT_NEAR(a.distortion.k2, b.distortion.k2, 1e-12);
}

void expectBagMatchesFolder(const std::string& bag_path, const FolderDataset& dataset, bool compressed) {
  BagImageReader reader(bag_path);
  EXPECT_EQ(reader.compressed(), compressed);
  ASSERT_EQ(reader.size(), dataset.size());
  ASSERT_TRUE(reader.hasCamera());
  EXPECT_EQ(reader.cameraInfoTopic(), "/camera/camera_info");
  expectSameCamera(reader.camera(), dataset.camera());
  BagFrame frame;
  for (std::size_t k = 0; k < dataset.size(); ++k) {
    ASSERT_TRUE(reader.next(frame));
    const cv::Mat expected = dataset.loadImage(k);
    ASSERT_EQ(frame.image.type(), expected.type());
    EXPECT_EQ(cv::norm(frame.image, expected, cv::NORM_INF), 0.0) << "frame " << k;
    EXPECT_NEAR(frame.stamp, dataset.timestamp(k), 1e-6);
    EXPECT_EQ(frame.frame_id, "camera_optical");
  }
  EXPECT_FALSE(reader.next(frame));
}

TEST(BagIo, FolderToBagToFramesIsLossless) {
  TempDir dir;
  writeSmallFlight(dir / "flight");
  const FolderDataset dataset(dir / "flight");
  FolderToBagOptions options;
  EXPECT_EQ(convertFolderToBag(dataset, dir / "raw.bag", options), dataset.size());
  expectBagMatchesFolder(dir / "raw.bag", dataset, false);

  options.writer.image_format = "png";
  options.writer.image_topic = "/camera/image_raw/compressed";
  options.writer.compression = "lz4";
  convertFolderToBag(dataset, dir / "png.bag", options);
  expectBagMatchesFolder(dir / "png.bag", dataset, true);
}

TEST(BagIo, FolderWithoutTimestampsGetsEvenStamps) {
  TempDir dir;
  writeSmallFlight(dir / "flight", 3);
  std::filesystem::remove(dir.path() / "flight" / "timestamps.txt");
  const FolderDataset dataset(dir / "flight");
  FolderToBagOptions options;
  options.rate = 4.0;
  options.start_time = 10.0;
  convertFolderToBag(dataset, dir / "even.bag", options);
  BagImageReader reader(dir / "even.bag", "/camera/image_raw");
  BagFrame frame;
  for (int k = 0; reader.next(frame); ++k) EXPECT_NEAR(frame.stamp, 10.0 + 0.25 * k, 1e-9);
}

// Writes one Image message of the given encoding holding `pixels` (as raw bytes).
void writeImageBag(const std::string& path, const std::string& encoding, const cv::Mat& pixels,
                   bool big_endian = false) {
  sensor_msgs::Image message;
  message.header.stamp = ros::Time(5.0);
  message.encoding = encoding;
  message.height = static_cast<std::uint32_t>(pixels.rows);
  message.width = static_cast<std::uint32_t>(pixels.cols);
  message.is_bigendian = big_endian ? 1 : 0;
  message.step = static_cast<std::uint32_t>(pixels.cols * pixels.elemSize() + 8);  // padded rows
  message.data.assign(static_cast<std::size_t>(message.step) * pixels.rows, 0);
  for (int r = 0; r < pixels.rows; ++r) {
    std::memcpy(&message.data[r * message.step], pixels.ptr(r), pixels.cols * pixels.elemSize());
  }
  rosbag::Bag bag(path, rosbag::bagmode::Write);
  bag.write("/cam/image", ros::Time(5.0), message);
}

cv::Mat readOnlyFrame(const std::string& path) {
  BagImageReader reader(path);
  EXPECT_FALSE(reader.hasCamera());
  BagFrame frame;
  EXPECT_TRUE(reader.next(frame));
  EXPECT_DOUBLE_EQ(frame.stamp, 5.0);
  return frame.image;
}

// What the estimator gets of each encoding: grey as OpenCV weighs colours (at 8 or 16 bits), or the
// pixels as stored for generic encodings.
TEST(BagIo, DecodesEveryCommonEncoding) {
  TempDir dir;
  cv::Mat3b bgr(4, 5);
  cv::randu(bgr, cv::Scalar::all(0), cv::Scalar::all(255));
  cv::Mat3b rgb;
  cv::cvtColor(bgr, rgb, cv::COLOR_BGR2RGB);
  cv::Mat4b bgra, rgba;
  cv::cvtColor(bgr, bgra, cv::COLOR_BGR2BGRA);
  cv::cvtColor(bgr, rgba, cv::COLOR_BGR2RGBA);
  cv::Mat1b mono8;
  cv::cvtColor(bgr, mono8, cv::COLOR_BGR2GRAY);
  cv::Mat1w mono16;
  mono8.convertTo(mono16, CV_16U, 257.0);
  cv::Mat3w bgr16;
  bgr.convertTo(bgr16, CV_16U, 257.0);
  cv::Mat1w grey16;
  cv::cvtColor(bgr16, grey16, cv::COLOR_BGR2GRAY);
  cv::Mat1f float32;
  mono8.convertTo(float32, CV_32F, 1.0 / 255.0);

  struct Case {
    const char* encoding;
    cv::Mat stored;
    cv::Mat expected;
  };
  const Case cases[] = {{"mono8", mono8, mono8}, {"mono16", mono16, mono16}, {"bgr8", bgr, mono8},
                        {"rgb8", rgb, mono8},    {"bgra8", bgra, mono8},     {"rgba8", rgba, mono8},
                        {"bgr16", bgr16, grey16}, {"32FC1", float32, float32}, {"8UC1", mono8, mono8},
                        {"8UC3", bgr, bgr}};
  for (const Case& c : cases) {
    const std::string path = dir / (std::string(c.encoding) + ".bag");
    writeImageBag(path, c.encoding, c.stored);
    const cv::Mat image = readOnlyFrame(path);
    ASSERT_EQ(image.type(), c.expected.type()) << c.encoding;
    EXPECT_EQ(cv::norm(image, c.expected, cv::NORM_INF), 0.0) << c.encoding;
  }
  // Big-endian 16-bit data, grey and colour.
  const auto swapped = [](const cv::Mat& image) {
    cv::Mat out = image.clone();
    for (int r = 0; r < out.rows; ++r) {
      auto* p = out.ptr<std::uint16_t>(r);
      for (int i = 0; i < out.cols * out.channels(); ++i) p[i] = static_cast<std::uint16_t>((p[i] >> 8) | (p[i] << 8));
    }
    return out;
  };
  writeImageBag(dir / "big.bag", "mono16", swapped(mono16), true);
  cv::Mat image = readOnlyFrame(dir / "big.bag");
  ASSERT_EQ(image.type(), CV_16UC1);
  EXPECT_EQ(cv::norm(image, mono16, cv::NORM_INF), 0.0);
  writeImageBag(dir / "big_bgr16.bag", "bgr16", swapped(bgr16), true);
  image = readOnlyFrame(dir / "big_bgr16.bag");
  ASSERT_EQ(image.type(), CV_16UC1);
  EXPECT_EQ(cv::norm(image, grey16, cv::NORM_INF), 0.0);
}

// A uniform colour seen through each Bayer pattern must come back as that colour's grey (a wrong
// pattern mapping swaps red and blue, or mixes in green, and changes the grey).
TEST(BagIo, DemosaicsBayerPatterns) {
  TempDir dir;
  const int blue = 30, green = 120, red = 200;
  cv::Mat1b grey;
  cv::cvtColor(cv::Mat3b(1, 1, cv::Vec3b(blue, green, red)), grey, cv::COLOR_BGR2GRAY);
  // The colour at (row, col) of each pattern: its name lists row 0 (two pixels), then row 1.
  const std::map<std::string, std::string> patterns = {
      {"bayer_rggb8", "rggb"}, {"bayer_bggr8", "bggr"}, {"bayer_gbrg8", "gbrg"}, {"bayer_grbg8", "grbg"}};
  for (const auto& [encoding, layout] : patterns) {
    cv::Mat1b mosaic(8, 8);
    for (int r = 0; r < mosaic.rows; ++r) {
      for (int c = 0; c < mosaic.cols; ++c) {
        const char colour = layout[(r % 2) * 2 + (c % 2)];
        mosaic(r, c) = static_cast<unsigned char>(colour == 'r' ? red : colour == 'g' ? green : blue);
      }
    }
    const std::string path = dir / (encoding + ".bag");
    writeImageBag(path, encoding, mosaic);
    const cv::Mat image = readOnlyFrame(path);
    ASSERT_EQ(image.type(), CV_8UC1) << encoding;
    EXPECT_NEAR(image.at<unsigned char>(4, 4), grey(0, 0), 2) << encoding;
  }
}

// Compressed images become grey at their own depth, as cv::imdecode and cvtColor make them.
TEST(BagIo, CompressedImagesBecomeGrey) {
  cv::Mat3b bgr(24, 32);
  cv::randu(bgr, cv::Scalar::all(0), cv::Scalar::all(255));
  cv::Mat1b grey;
  cv::cvtColor(bgr, grey, cv::COLOR_BGR2GRAY);
  cv::Mat3w bgr16;
  bgr.convertTo(bgr16, CV_16U, 257.0);
  cv::Mat1w grey16;
  cv::cvtColor(bgr16, grey16, cv::COLOR_BGR2GRAY);
  const auto compressed = [](const std::string& format, const cv::Mat& image) {
    sensor_msgs::CompressedImage message;
    message.format = format;
    EXPECT_TRUE(cv::imencode("." + format, image, message.data));
    return message;
  };
  struct Case {
    std::string format;
    cv::Mat stored, expected;
  };
  for (const Case& c : {Case{"png", grey, grey}, Case{"png", bgr, grey}, Case{"png", grey16, grey16},
                        Case{"png", bgr16, grey16}}) {
    const cv::Mat image = imageFromMessage(compressed(c.format, c.stored));
    ASSERT_EQ(image.type(), c.expected.type()) << cv::typeToString(c.stored.type());
    EXPECT_EQ(cv::norm(image, c.expected, cv::NORM_INF), 0.0) << cv::typeToString(c.stored.type());
  }
  // JPEG: the grey of what cv::imdecode makes of the file.
  const sensor_msgs::CompressedImage jpeg = compressed("jpg", bgr);
  cv::Mat1b expected;
  cv::cvtColor(cv::imdecode(jpeg.data, cv::IMREAD_UNCHANGED), expected, cv::COLOR_BGR2GRAY);
  EXPECT_EQ(cv::norm(imageFromMessage(jpeg), expected, cv::NORM_INF), 0.0);
}

void expectBagError(const std::function<void()>& action, const std::string& fragment) {
  try {
    action();
    ADD_FAILURE() << "no BagError";
  } catch (const BagError& e) {
    EXPECT_NE(std::string(e.what()).find(fragment), std::string::npos) << e.what();
  }
}

TEST(BagIo, ClearErrors) {
  TempDir dir;
  writeImageBag(dir / "nv21.bag", "nv21", cv::Mat1b(6, 4, static_cast<unsigned char>(0)));
  BagImageReader reader(dir / "nv21.bag");
  BagFrame frame;
  expectBagError([&] { reader.next(frame); }, "unsupported image encoding 'nv21'");
  expectBagError([&] { reader.next(frame); }, "topic '/cam/image' of bag");

  expectBagError([&] { BagImageReader(dir / "nv21.bag", "/missing"); }, "has no topic '/missing'");
  expectBagError([&] { BagImageReader(dir / "nv21.bag", "", "/info"); }, "no CameraInfo topic '/info'");
  std::ofstream(dir / "text.bag") << "not a bag";
  expectBagError([&] { BagImageReader(dir / "text.bag"); }, "text.bag");
  expectBagError([&] { BagImageReader(dir / "nothing.bag"); }, "nothing.bag");

  {  // two image topics: the reader cannot guess
    rosbag::Bag bag(dir / "two.bag", rosbag::bagmode::Write);
    const sensor_msgs::Image image = imageMessage(cv::Mat1b(2, 2, static_cast<unsigned char>(1)), 1.0, "a");
    bag.write("/a/image", ros::Time(1.0), image);
    bag.write("/b/image", ros::Time(1.0), image);
  }
  expectBagError([&] { BagImageReader(dir / "two.bag"); }, "2 image topics");
  EXPECT_EQ(BagImageReader(dir / "two.bag", "/b/image").size(), 1u);

  const sensor_msgs::Image good = imageMessage(cv::Mat1b(4, 4, static_cast<unsigned char>(1)), 1.0, "a");
  sensor_msgs::Image message = good;
  message.data.resize(10);
  expectBagError([&] { imageFromMessage(message); }, "'mono8' image of 4x4 has step 4 and 10 bytes: too few");
  message.data.resize(20);
  expectBagError([&] { imageFromMessage(message); }, "too many");
  message = good;
  message.step = 3;
  expectBagError([&] { imageFromMessage(message); }, "a row needs 4");
  message = good;
  message.width = 0;
  expectBagError([&] { imageFromMessage(message); }, "no pixels");
  message = good;
  message.height = 0;
  message.data.clear();
  expectBagError([&] { imageFromMessage(message); }, "no pixels");
  message = good;
  message.width = 3000000000u;
  expectBagError([&] { imageFromMessage(message); }, "too large");
  message = good;
  message.height = (1u << 28) + 1;  // height x step wraps in 32 bits to the data's size
  message.step = 16;
  message.data.resize(16);
  expectBagError([&] { imageFromMessage(message); }, "too few");
  message = imageMessage(cv::Mat1w(4, 4, static_cast<std::uint16_t>(1)), 1.0, "a");
  message.step = 9;
  message.data.resize(36);
  expectBagError([&] { imageFromMessage(message); }, "has step 9: not a multiple of its 2-byte channel values");
  message = good;
  message.encoding = "8UC2";
  message.width = 2;
  expectBagError([&] { imageFromMessage(message); }, "unsupported image encoding '8UC2'");
  message.encoding = "16SC1";
  expectBagError([&] { imageFromMessage(message); }, "unsupported image encoding '16SC1'");
  message.encoding = "";
  expectBagError([&] { imageFromMessage(message); }, "unsupported image encoding ''");

  sensor_msgs::CompressedImage garbage;
  garbage.format = "png";
  garbage.data = {1, 2, 3};
  expectBagError([&] { imageFromMessage(garbage); }, "cannot decode compressed image (format 'png', 3 bytes)");
  garbage.data.clear();
  expectBagError([&] { imageFromMessage(garbage); }, "no data");

  CameraParameters camera;
  camera.intrinsics = {100, 100, 50, 50, 100, 100};
  BagFlightWriter writer(dir / "w.bag", camera, BagWriterOptions{});
  expectBagError([&] { writer.write(cv::Mat1b(4, 4), 0.0); }, "> 0");
  expectBagError([&] { writer.write(cv::Mat2f(4, 4), 1.0); }, "cannot store");
  BagWriterOptions bad;
  bad.compression = "zip";
  expectBagError([&] { BagFlightWriter(dir / "x.bag", camera, bad); }, "compression");
}

TEST(BagIo, CameraInfoRoundTrip) {
  CameraParameters camera;
  camera.intrinsics = {410.5, 411.25, 255.5, 250.0, 512, 500};
  camera.distortion = {-0.2, 0.05, 0.001, 0.002};
  const sensor_msgs::CameraInfo info = cameraInfoMessage(camera, 3.0, "cam");
  EXPECT_EQ(info.distortion_model, "plumb_bob");
  EXPECT_EQ(info.D.size(), 5u);
  const CameraParameters back = cameraFromInfo(info);
  expectSameCamera(back, camera);
  EXPECT_EQ(back.distortion.p2, 0.002);
  sensor_msgs::CameraInfo uncalibrated;
  EXPECT_THROW(cameraFromInfo(uncalibrated), BagError);
}

// A binned camera, or one sending a region of interest: the intrinsics of the images it sends.
TEST(BagIo, CameraInfoOfBinnedAndCroppedImages) {
  CameraParameters camera;
  camera.intrinsics = {800.0, 804.0, 639.5, 479.5, 1280, 960};
  sensor_msgs::CameraInfo info = cameraInfoMessage(camera, 3.0, "cam");
  info.binning_x = info.binning_y = 2;
  CameraParameters binned = cameraFromInfo(info);
  EXPECT_DOUBLE_EQ(binned.intrinsics.fx, 400.0);
  EXPECT_DOUBLE_EQ(binned.intrinsics.fy, 402.0);
  EXPECT_DOUBLE_EQ(binned.intrinsics.cx, 319.75);
  EXPECT_EQ(binned.intrinsics.width, 640);
  EXPECT_EQ(binned.intrinsics.height, 480);
  info.binning_x = info.binning_y = 0;
  info.roi.x_offset = 100;
  info.roi.y_offset = 40;
  info.roi.width = 640;
  info.roi.height = 480;
  const CameraParameters cropped = cameraFromInfo(info);
  EXPECT_DOUBLE_EQ(cropped.intrinsics.fx, 800.0);
  EXPECT_DOUBLE_EQ(cropped.intrinsics.cx, 539.5);
  EXPECT_DOUBLE_EQ(cropped.intrinsics.cy, 439.5);
  EXPECT_EQ(cropped.intrinsics.width, 640);
  EXPECT_EQ(cropped.intrinsics.height, 480);
}

// The models both programs take (through OpenCV), and a clear error naming any other.
TEST(BagIo, CameraInfoDistortionModels) {
  CameraParameters camera;
  camera.intrinsics = {410.5, 411.25, 255.5, 250.0, 512, 500};
  camera.distortion.k1 = -0.3;
  camera.distortion.k3 = 0.02;
  sensor_msgs::CameraInfo info = cameraInfoMessage(camera, 3.0, "cam");
  EXPECT_EQ(info.distortion_model, "plumb_bob");
  EXPECT_EQ(cameraFromInfo(info).distortion.k3, 0.02);
  camera.distortion.k4 = 0.1;
  camera.distortion.k6 = -0.01;
  info = cameraInfoMessage(camera, 3.0, "cam");
  EXPECT_EQ(info.distortion_model, "rational_polynomial");
  ASSERT_EQ(info.D.size(), 8u);
  const CameraParameters rational = cameraFromInfo(info);
  EXPECT_EQ(rational.distortion.k4, 0.1);
  EXPECT_EQ(rational.distortion.k6, -0.01);
  // Uncalibrated drivers: no model, no (or zero) coefficients.
  info.distortion_model = "";
  info.D.clear();
  EXPECT_FALSE(cameraFromInfo(info).distortion.any());
  info.D = {0.0, 0.0, 0.0, 0.0, 0.0};
  EXPECT_FALSE(cameraFromInfo(info).distortion.any());
  // A fisheye is not a pinhole, even without coefficients.
  info.distortion_model = "equidistant";
  expectBagError([&] { cameraFromInfo(info); }, "distortion model 'equidistant' is not supported");
  info.D.clear();
  expectBagError([&] { cameraFromInfo(info); }, "'equidistant'");
  info.distortion_model = "";
  info.D = {-0.1, 0.0, 0.0, 0.0, 0.0};
  expectBagError([&] { cameraFromInfo(info); }, "distortion model '' is not supported");
  // plumb_bob has five coefficients: more (non-zero) ones would be dropped silently.
  info.distortion_model = "plumb_bob";
  info.D = {-0.1, 0.0, 0.0, 0.0, 0.0, 0.3};
  expectBagError([&] { cameraFromInfo(info); }, "6 distortion coefficients; plumb_bob has 5");
  info.D = {-0.1, std::nan(""), 0.0, 0.0, 0.0};
  expectBagError([&] { cameraFromInfo(info); }, "not finite");
}

// A bag whose CameraInfo cannot be used stops oefmt_offline's reader at once, naming the bag,
// the topic and the problem.
TEST(BagIo, UnusableCameraInfoIsNamedWithItsTopic) {
  TempDir dir;
  {
    rosbag::Bag bag(dir / "fisheye.bag", rosbag::bagmode::Write);
    bag.write("/cam/image", ros::Time(1.0), imageMessage(cv::Mat1b(64, 64, static_cast<unsigned char>(1)), 1.0, "c"));
    CameraParameters camera;
    camera.intrinsics = {50.0, 50.0, 31.5, 31.5, 64, 64};
    sensor_msgs::CameraInfo info = cameraInfoMessage(camera, 1.0, "c");
    info.distortion_model = "equidistant";
    info.D = {0.1, 0.01, 0.0, 0.0};
    bag.write("/cam/camera_info", ros::Time(1.0), info);
  }
  expectBagError([&] { BagImageReader(dir / "fisheye.bag"); },
                 "fisheye.bag', /cam/camera_info: CameraInfo distortion model 'equidistant' is not supported");
  EXPECT_FALSE(BagImageReader(dir / "fisheye.bag", "", "-").hasCamera());  // intrinsics ignored
}

TEST(BagIo, SimulatorBagCarriesTheFlightsCamera) {
  TempDir dir;
  sim::FlightOptions options;
  options.width = options.height = 80;
  options.track.frames = 3;
  options.track.length = 10.0;
  options.distortion.k2 = 0.01;
  const sim::FlightPlan plan = sim::planFlight(options);
  {
    BagFlightWriter writer(dir / "sim.bag", plan.camera, BagWriterOptions{});
    sim::renderFlight(plan, [&](int k, const cv::Mat1b& image, const cv::Mat1b&) { writer.write(image, plan.stamps[k]); });
    EXPECT_EQ(writer.written(), 3u);
  }
  BagImageReader reader(dir / "sim.bag");
  EXPECT_EQ(reader.imageTopic(), "/camera/image_raw");
  expectSameCamera(reader.camera(), plan.camera);
  BagFrame frame;
  ASSERT_TRUE(reader.next(frame));
  EXPECT_EQ(frame.encoding, "mono8");
  EXPECT_DOUBLE_EQ(frame.stamp, plan.stamps[0]);
}

TEST(BagIo, AnImuWithoutRatesGivesNoGyroTurn) {
  ImuSample truth;
  truth.stamp = 1.0;
  truth.angular_velocity = {0.0, 0.0, 0.4};  // turning at 0.4 rad/s
  sensor_msgs::Imu message = imuMessage(truth, "imu");
  const ImuSample with_rates = imuSample(message);
  EXPECT_DOUBLE_EQ(with_rates.angular_velocity.z(), 0.4);
  // sensor_msgs/Imu: a covariance of -1 says the element was not measured. Read as zero rates,
  // the gyro would say the vehicle holds its heading, and every pair would be searched there.
  message.angular_velocity_covariance[0] = -1.0;
  const ImuSample without = imuSample(message);
  EXPECT_TRUE(without.angular_velocity.array().isNaN().all());
  TurnHistory turns;
  for (int k = 0; k <= 40; ++k) {
    ImuSample s = without;
    s.stamp = 1.0 + 0.005 * k;
    turns.add(s.stamp, s.orientation, s.angular_velocity);
  }
  EXPECT_FALSE(turns.turn(1.0, 1.2).has_value());
}

}  // namespace
}  // namespace oefmt
