// SPDX-License-Identifier: GPL-3.0-or-later
#include "frame_source.h"

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "oefmt/error.h"
#include "oefmt/io/image_decoding.h"

namespace oefmt {
namespace {

// How many frames ahead a folder's images are read in the background.
constexpr std::size_t kReadAhead = 4;

class FolderSource : public FrameSource {
 public:
  explicit FolderSource(const std::string& directory) : dataset_(directory) {}
  std::size_t size() const override { return dataset_.size(); }
  bool next(SourceFrame& frame) override {
    if (index_ >= dataset_.size()) return false;
    frame.index = index_;
    // timestamps.txt's seconds (the motion model needs the frame interval), else the frame index
    // (as the authors' ground truth is indexed).
    frame.stamp = dataset_.timestamp(index_);
    frame.name = dataset_.imageName(index_);
    // The files a few frames ahead are read in the background meanwhile: where they are not in
    // the page cache yet (a flight's first run), the reader would otherwise wait for the disk at
    // every frame.
    for (std::size_t ahead = index_ == 0 ? 1 : kReadAhead; ahead <= kReadAhead; ++ahead) {
      dataset_.adviseReading(index_ + ahead);
    }
    frame.image = dataset_.loadImage(index_);
    ++index_;
    return true;
  }
  std::optional<CameraParameters> calibration() const override {
    return CameraParameters{dataset_.fileIntrinsics(), dataset_.distortion()};
  }
  std::string calibrationSource() const override { return "cam_param.yaml"; }
  cv::Size imageSize() override { return dataset_.imageSize(); }
  std::vector<std::string> warnings() const override { return dataset_.warnings(); }
  std::string describe() const override {
    return dataset_.directory() + " (" + std::to_string(dataset_.size()) + " images " +
           std::to_string(dataset_.imageSize().width) + "x" +
           std::to_string(dataset_.imageSize().height) + ")";
  }
  const FolderDataset& dataset() const { return dataset_; }

 private:
  FolderDataset dataset_;
  std::size_t index_ = 0;
};

}  // namespace

std::unique_ptr<FrameSource> openFolder(const std::string& directory) {
  return std::make_unique<FolderSource>(directory);
}

PrefetchingSource::PrefetchingSource(std::unique_ptr<FrameSource> source, std::size_t depth,
                                     Analyse analyse, Analyse spare)
    : source_(std::move(source)),
      depth_(depth == 0 ? 1 : depth),
      analyse_(std::move(analyse)),
      spare_(std::move(spare)) {
  thread_ = std::thread(&PrefetchingSource::run, this);
}

PrefetchingSource::~PrefetchingSource() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  changed_.notify_all();
  thread_.join();
}

void PrefetchingSource::run() {
  for (;;) {
    SourceFrame frame;
    bool more = false;
    std::exception_ptr error;
    try {
      more = source_->next(frame);
      if (more) frame.image_size = frame.image.size();
      if (more && analyse_) {
        try {
          analyse_(frame);
          if (spare_ && consumerHasWork()) spare_(frame);
        } catch (const InputError& e) {
          throw InputError(frame.name + ": " + e.what());  // which frame, for the user
        }
        frame.image.release();
      }
    } catch (...) {
      error = std::current_exception();
    }
    std::unique_lock<std::mutex> lock(mutex_);
    if (error || !more) {
      error_ = error;
      finished_ = true;
      changed_.notify_all();
      return;
    }
    changed_.wait(lock, [this] { return queue_.size() < depth_ || stopping_; });
    if (stopping_) return;
    queue_.push_back(std::move(frame));
    changed_.notify_all();
  }
}

bool PrefetchingSource::consumerHasWork() {
  std::lock_guard<std::mutex> lock(mutex_);
  return !queue_.empty();
}

bool PrefetchingSource::next(SourceFrame& frame) {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [this] { return !queue_.empty() || finished_; });
  if (!queue_.empty()) {
    frame = std::move(queue_.front());
    queue_.pop_front();
    changed_.notify_all();
    return true;
  }
  if (error_) std::rethrow_exception(error_);
  return false;
}

}  // namespace oefmt
