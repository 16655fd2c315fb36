// SPDX-License-Identifier: GPL-3.0-or-later
// oefmt_folder_to_bag: converts a dataset in the o-eFMT authors' folder layout to a ROS bag
// (sensor_msgs/Image or CompressedImage + CameraInfo), so existing datasets replay in ROS.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <string>
#include <vector>

#include "oefmt/io/dataset.h"
#include "command_line.h"
#include "oefmt/error.h"
#include "oefmt/ros/bag_io.h"
#include "progress.h"

namespace {

struct Command {
  oefmt::FolderToBagOptions options;
  std::string dataset, bag;
  bool quiet = false;
};

/// Reads the command line into `c`; returns the exit status when the tool is to stop here.
std::optional<int> parse(int argc, char** argv, Command& c) {
  CLI::App app(R"(Reads DATASET_DIR in the o-eFMT authors' layout (Images/, imageList.txt, optional
timestamps.txt, cam_param.yaml) and writes every image, as stored, with a CameraInfo of the same
stamp. cam_param.yaml's intrinsics (of the original camera, e.g. 4056x3040) are scaled to the
images' size (centred crop to their aspect, then resize) and written as CameraInfo K/P, with
D = (k1, k2, p1, p2, k3) plumb_bob (rational_polynomial with k4..k6 when cam_param.yaml has them).)",
               "oefmt_folder_to_bag");
  oefmt::tools::setUpTool(app, "exit codes: 0 success, 1 read/write failure, 2 invalid option");
  oefmt::BagWriterOptions& writer = c.options.writer;
  app.add_option("DATASET_DIR", c.dataset, "the dataset folder")->type_name("")->required();
  app.add_option("OUTPUT.bag", c.bag, "the bag to write")->type_name("")->required();
  const CLI::Option* topic = app.add_option("--image-topic", writer.image_topic,
                                            "image topic (default /camera/image_raw; /camera/image_raw/compressed\n"
                                            "with --format png|jpg)")
                                 ->type_name("T");
  app.add_option("--info-topic", writer.camera_info_topic, "CameraInfo topic (default /camera/camera_info)")
      ->type_name("T");
  app.add_option("--frame-id", writer.frame_id, "header frame_id (default camera_optical)")->type_name("F");
  // BagWriterOptions says raw as an empty format.
  oefmt::tools::addChoice(app, "--format", writer.image_format,
                          {{"raw", std::string()}, {"png", "png"}, {"jpg", "jpg"}},
                          "raw sensor_msgs/Image (default) or sensor_msgs/CompressedImage");
  oefmt::tools::addChoice(app, "--compression", writer.compression, {"none", "lz4", "bz2"},
                          "bag chunk compression (default none)");
  oefmt::tools::addNumber(app, "--rate", c.options.rate, "HZ",
                          "without usable timestamps.txt: stamp k = start + k / rate (default 5)");
  oefmt::tools::addNumber(app, "--start-time", c.options.start_time, "S", "(default 1.0)");
  app.add_flag("--quiet", c.quiet, "print nothing but errors");
  app.callback([&c, &writer, topic] {
    oefmt::requireInput(c.options.rate > 0.0 && c.options.start_time > 0.0, "--rate and --start-time must be > 0");
    if (!writer.image_format.empty() && topic->count() == 0) writer.image_topic = "/camera/image_raw/compressed";
  });
  return oefmt::tools::parseCommandLine(app, argc, argv);
}

}  // namespace

int main(int argc, char** argv) {
  Command command;
  if (const std::optional<int> exit_status = parse(argc, argv, command)) return *exit_status;

  try {
    const oefmt::FolderDataset dataset(command.dataset);
    for (const std::string& warning : dataset.warnings()) std::fprintf(stderr, "oefmt_folder_to_bag: note: %s\n", warning.c_str());
    if (!command.quiet) {
      const oefmt::Intrinsics& file = dataset.fileIntrinsics();
      const oefmt::Intrinsics& k = dataset.intrinsics();
      std::printf("dataset     %s: %zu images of %dx%d, %s\n", command.dataset.c_str(), dataset.size(), k.width,
                  k.height, dataset.hasTimestamps() ? "stamps from timestamps.txt" : "stamps start + k / rate");
      std::printf("intrinsics  file %dx%d fx %.2f fy %.2f cx %.2f cy %.2f -> images fx %.3f fy %.3f cx %.3f cy %.3f\n",
                  file.width, file.height, file.fx, file.fy, file.cx, file.cy, k.fx, k.fy, k.cx, k.cy);
    }
    oefmt::tools::ProgressBar progress("converting", dataset.size(), command.quiet ? nullptr : stderr);
    const std::size_t frames = oefmt::convertFolderToBag(dataset, command.bag, command.options,
                                                         [&](std::size_t k) { progress.update(k + 1); });
    progress.finish();
    if (!command.quiet) {
      const oefmt::BagWriterOptions& writer = command.options.writer;
      std::printf("wrote       %s: %zu frames on %s (%s) + %s\n", command.bag.c_str(), frames,
                  writer.image_topic.c_str(),
                  writer.image_format.empty() ? "sensor_msgs/Image" : "sensor_msgs/CompressedImage",
                  writer.camera_info_topic.c_str());
    }
    return 0;
  } catch (const std::exception& e) {  // DatasetError, BagError, InputError
    std::fprintf(stderr, "oefmt_folder_to_bag: %s\n", e.what());
    return 1;
  }
}
