// SPDX-License-Identifier: GPL-3.0-or-later
#include "frame_source.h"

#include <dlfcn.h>

#include <filesystem>
#include <optional>
#include <stdexcept>
#include <utility>
#include <vector>

#include "oefmt/error.h"
#include "oefmt/io/image_decoding.h"

namespace oefmt {
namespace {

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

// oefmt_offline reads bags through a plugin, loaded for the first bag: linked, the ROS libraries
// and cv_bridge (which brings OpenCV's imgcodecs and its ~150 libraries) would cost every run,
// folders included, ~0.2 s of start-up and ~40 MB.
constexpr const char* kBagSourceModuleFile = "liboefmt_bag_source.so";
using OpenBagSource = FrameSource* (*)(const std::string& path, const std::string& image_topic,
                                       const std::string& camera_info_topic);

OpenBagSource loadBagSourceModule() {
  static const std::pair<OpenBagSource, std::string> loaded = [] {
    std::vector<std::string> candidates;
    // Built and installed beside liboefmt_io.so (the executables are a folder below).
    Dl_info info{};
    if (::dladdr(reinterpret_cast<const void*>(&decodeImage), &info) != 0 && info.dli_fname != nullptr) {
      candidates.push_back((std::filesystem::path(info.dli_fname).parent_path() / kBagSourceModuleFile).string());
    }
    candidates.emplace_back(kBagSourceModuleFile);  // LD_LIBRARY_PATH, the loader's cache
    std::string errors;
    for (const std::string& candidate : candidates) {
      void* handle = ::dlopen(candidate.c_str(), RTLD_NOW | RTLD_LOCAL);
      if (handle == nullptr) {
        const char* reason = ::dlerror();
        errors += "\n  " + (reason ? std::string(reason) : candidate + ": not loadable");
        continue;
      }
      // The symbol names the interface's version: a stale plugin is not found, so not called.
      if (void* entry = ::dlsym(handle, kBagSourceModuleSymbol)) {
        return std::make_pair(reinterpret_cast<OpenBagSource>(entry), std::string());  // kept loaded
      }
      errors += "\n  " + candidate + ": not this version's plugin (rebuild oefmt)";
      ::dlclose(handle);
    }
    return std::make_pair(OpenBagSource{nullptr}, std::string("cannot load the bag reader plugin ") +
                                                     kBagSourceModuleFile + " (built and installed with oefmt):" +
                                                     errors);
  }();
  if (loaded.first == nullptr) throw std::runtime_error(loaded.second);
  return loaded.first;
}

}  // namespace

std::unique_ptr<FrameSource> openFolder(const std::string& directory) {
  return std::make_unique<FolderSource>(directory);
}

std::unique_ptr<FrameSource> openBag(const std::string& path, const std::string& image_topic,
                                     const std::string& camera_info_topic) {
  return std::unique_ptr<FrameSource>(loadBagSourceModule()(path, image_topic, camera_info_topic));
}

PrefetchingSource::PrefetchingSource(std::unique_ptr<FrameSource> source, std::size_t depth,
                                     Analyse analyse)
    : source_(std::move(source)), depth_(depth == 0 ? 1 : depth), analyse_(std::move(analyse)) {
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
          frame.spectra = analyse_(frame.image);
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
