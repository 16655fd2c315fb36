// SPDX-License-Identifier: GPL-3.0-or-later
// oefmt_folder_to_bag: converts a dataset in the o-eFMT authors' folder layout to a ROS bag
// (sensor_msgs/Image or CompressedImage + CameraInfo), so existing datasets replay in ROS.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "oefmt/io/dataset.h"
#include "command_line.h"
#include "oefmt/error.h"
#include "oefmt/ros/bag_io.h"
#include "progress.h"

namespace {

const char* const kUsage = R"(usage: oefmt_folder_to_bag [options] DATASET_DIR OUTPUT.bag

Reads DATASET_DIR in the o-eFMT authors' layout (Images/, imageList.txt, optional
timestamps.txt, cam_param.yaml) and writes every image, as stored, with a CameraInfo of the same
stamp. cam_param.yaml's intrinsics (of the original camera, e.g. 4056x3040) are scaled to the
images' size (centred crop to their aspect, then resize) and written as CameraInfo K/P, with
D = (k1, k2, p1, p2, k3) plumb_bob (rational_polynomial with k4..k6 when cam_param.yaml has them).

options:
  --image-topic T      image topic (default /camera/image_raw; /camera/image_raw/compressed
                       with --format png|jpg)
  --info-topic T       CameraInfo topic (default /camera/camera_info)
  --frame-id F         header frame_id (default camera_optical)
  --format raw|png|jpg raw sensor_msgs/Image (default) or sensor_msgs/CompressedImage
  --compression C      bag chunk compression: none (default), lz4, bz2
  --rate HZ            without usable timestamps.txt: stamp k = start + k / rate (default 5)
  --start-time S       (default 1.0)
  --quiet              print nothing but errors
  -h, --help
exit codes: 0 success, 1 read/write failure, 2 invalid option)";


}  // namespace

int main(int argc, char** argv) {
  oefmt::FolderToBagOptions options;
  bool quiet = false, topic_set = false;
  std::string format = "raw";
  std::vector<std::string> paths;
  try {
    oefmt::tools::Arguments args(argc, argv);
    while (!args.done()) {
      const std::string arg = args.take();
      const auto value = [&]() { return args.value(arg); };
      if (arg == "-h" || arg == "--help") {
        std::puts(kUsage);
        return 0;
      } else if (arg == "--image-topic") {
        options.writer.image_topic = value();
        topic_set = true;
      } else if (arg == "--info-topic") {
        options.writer.camera_info_topic = value();
      } else if (arg == "--frame-id") {
        options.writer.frame_id = value();
      } else if (arg == "--format") {
        format = value();
        if (format != "raw" && format != "png" && format != "jpg") throw oefmt::InputError("--format must be raw, png or jpg");
      } else if (arg == "--compression") {
        options.writer.compression = value();
      } else if (arg == "--rate") {
        options.rate = args.number(arg);
      } else if (arg == "--start-time") {
        options.start_time = args.number(arg);
      } else if (arg == "--quiet") {
        quiet = true;
      } else if (!arg.empty() && arg[0] == '-') {
        throw oefmt::InputError("unknown option '" + arg + "' (see --help)");
      } else {
        paths.push_back(arg);
      }
    }
    if (paths.size() != 2) throw oefmt::InputError("expected DATASET_DIR and OUTPUT.bag (see --help)");
    if (!(options.rate > 0.0) || !(options.start_time > 0.0)) throw oefmt::InputError("--rate and --start-time must be > 0");
    if (format != "raw") {
      options.writer.image_format = format;
      if (!topic_set) options.writer.image_topic = "/camera/image_raw/compressed";
    }
  } catch (const oefmt::InputError& e) {
    std::fprintf(stderr, "oefmt_folder_to_bag: %s\n", e.what());
    return 2;
  }

  try {
    const oefmt::FolderDataset dataset(paths[0]);
    for (const std::string& warning : dataset.warnings()) std::fprintf(stderr, "oefmt_folder_to_bag: note: %s\n", warning.c_str());
    if (!quiet) {
      const oefmt::Intrinsics& file = dataset.fileIntrinsics();
      const oefmt::Intrinsics& k = dataset.intrinsics();
      std::printf("dataset     %s: %zu images of %dx%d, %s\n", paths[0].c_str(), dataset.size(), k.width, k.height,
                  dataset.hasTimestamps() ? "stamps from timestamps.txt" : "stamps start + k / rate");
      std::printf("intrinsics  file %dx%d fx %.2f fy %.2f cx %.2f cy %.2f -> images fx %.3f fy %.3f cx %.3f cy %.3f\n",
                  file.width, file.height, file.fx, file.fy, file.cx, file.cy, k.fx, k.fy, k.cx, k.cy);
    }
    oefmt::tools::ProgressBar progress("converting", dataset.size(), quiet ? nullptr : stderr);
    const std::size_t frames = oefmt::convertFolderToBag(dataset, paths[1], options,
                                                         [&](std::size_t k) { progress.update(k + 1); });
    progress.finish();
    if (!quiet) {
      std::printf("wrote       %s: %zu frames on %s (%s) + %s\n", paths[1].c_str(), frames,
                  options.writer.image_topic.c_str(), format == "raw" ? "sensor_msgs/Image" : "sensor_msgs/CompressedImage",
                  options.writer.camera_info_topic.c_str());
    }
    return 0;
  } catch (const std::exception& e) {  // DatasetError, BagError, InputError
    std::fprintf(stderr, "oefmt_folder_to_bag: %s\n", e.what());
    return 1;
  }
}
