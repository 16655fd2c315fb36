// SPDX-License-Identifier: GPL-3.0-or-later
// oefmt_offline's frames from a bag (see openBag in frame_source.h).
#include <memory>
#include <optional>
#include <string>
#include <utility>

#include "frame_source.h"
#include "oefmt/ros/bag_io.h"

namespace oefmt {
namespace {

class BagSource : public FrameSource {
 public:
  BagSource(const std::string& path, const std::string& image_topic,
            const std::string& camera_info_topic)
      : path_(path), reader_(path, image_topic, camera_info_topic) {}
  std::size_t size() const override { return reader_.size(); }
  bool next(SourceFrame& frame) override {
    BagFrame bag_frame;
    if (first_) {
      bag_frame = std::move(*first_);
      first_.reset();
    } else if (!reader_.next(bag_frame)) {
      return false;
    }
    frame.index = index_++;
    frame.stamp = bag_frame.stamp;
    frame.name = reader_.imageTopic() + " message " + std::to_string(frame.index);
    frame.image = bag_frame.image;
    return true;
  }
  std::optional<CameraParameters> calibration() const override {
    if (!reader_.hasCamera()) return std::nullopt;
    return reader_.camera();
  }
  std::string calibrationSource() const override { return "CameraInfo on " + reader_.cameraInfoTopic(); }
  cv::Size imageSize() override {
    // The first frame is decoded now and handed out by the first next().
    if (index_ == 0 && !first_) {
      BagFrame frame;
      if (!reader_.next(frame)) return {};
      first_ = std::move(frame);
    }
    return first_ ? first_->image.size() : cv::Size();
  }
  std::string describe() const override {
    return path_ + " (" + std::to_string(reader_.size()) + " messages on " + reader_.imageTopic() +
           (reader_.hasCamera() ? ", intrinsics from " + reader_.cameraInfoTopic() : "") + ")";
  }

 private:
  std::string path_;
  BagImageReader reader_;
  std::optional<BagFrame> first_;  // read ahead by imageSize()
  std::size_t index_ = 0;
};

}  // namespace

std::unique_ptr<FrameSource> openBag(const std::string& path, const std::string& image_topic,
                                     const std::string& camera_info_topic) {
  return std::make_unique<BagSource>(path, image_topic, camera_info_topic);
}

}  // namespace oefmt
