// SPDX-License-Identifier: GPL-3.0-or-later
// Frames for oefmt_offline from a dataset folder or a bag, decoded (and optionally analysed) on
// a background thread so that decoding and the frame's FFTs overlap the estimation of the
// previous frame (a bounded queue: memory stays flat).
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/estimation/attitude.h"
#include "oefmt/io/dataset.h"
#include "oefmt/registration/spectra.h"

namespace oefmt {

struct SourceFrame {
  std::size_t index = 0;
  double stamp = 0.0;    ///< [s]: timestamps.txt (else the frame index) for folders, header stamp for bags
  cv::Mat image;         ///< as decoded; released once `spectra` is made
  cv::Size image_size;   ///< of the decoded image (kept when the image is released)
  FrameSpectra spectra;  ///< made by PrefetchingSource's `analyse`, when it has one
  std::optional<CameraTilt> tilt;  ///< the camera's roll and pitch when `analyse` undid them
  std::string name;      ///< file name or "bag message k"
};

/// Where frames come from. next() throws (with the file or bag named) on an unreadable frame.
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual std::size_t size() const = 0;
  virtual bool next(SourceFrame& frame) = 0;
  /// The calibration that comes with the frames (cam_param.yaml, the bag's CameraInfo) for its
  /// own resolution (intrinsics.width/height; 0 when it gives none); nullopt when there is none.
  virtual std::optional<CameraParameters> calibration() const { return std::nullopt; }
  /// Where calibration() comes from, for messages ("cam_param.yaml", "CameraInfo on /c/info").
  virtual std::string calibrationSource() const { return "the calibration"; }
  /// Size of the frames (the first one's; a bag decodes it ahead), empty when there is none.
  /// Called before the first next().
  virtual cv::Size imageSize() { return {}; }
  /// What the source tolerated and the user should know (a timestamps.txt that was ignored).
  virtual std::vector<std::string> warnings() const { return {}; }
  virtual std::string describe() const = 0;
};

std::unique_ptr<FrameSource> openFolder(const std::string& directory);
/// A bag's frames (oefmt/ros/bag_io.h's BagImageReader; src/tools/bag_source.cpp). Throws
/// BagError for the bag.
std::unique_ptr<FrameSource> openBag(const std::string& path, const std::string& image_topic,
                                     const std::string& camera_info_topic);

/// Reads ahead from a source on its own thread, at most `depth` frames. With `analyse`, each
/// frame's spectra are made on that thread too (`analyse` sets frame.spectra, and frame.tilt when
/// it levels the frame; the decoded image is released after it). `spare` runs after `analyse`
/// only while the consumer still has a frame queued, so that it does not wait for this one:
/// work the consumer would otherwise do itself, taken over only when the reader is ahead.
class PrefetchingSource {
 public:
  using Analyse = std::function<void(SourceFrame& frame)>;
  PrefetchingSource(std::unique_ptr<FrameSource> source, std::size_t depth = 4,
                    Analyse analyse = nullptr, Analyse spare = nullptr);
  ~PrefetchingSource();
  PrefetchingSource(const PrefetchingSource&) = delete;
  PrefetchingSource& operator=(const PrefetchingSource&) = delete;

  /// The next frame; false at the end. Rethrows the reader's error at the frame it happened.
  bool next(SourceFrame& frame);
  const FrameSource& source() const { return *source_; }

 private:
  void run();
  bool consumerHasWork();

  std::unique_ptr<FrameSource> source_;
  std::size_t depth_;
  Analyse analyse_;
  Analyse spare_;
  std::mutex mutex_;
  std::condition_variable changed_;
  std::deque<SourceFrame> queue_;
  bool finished_ = false;
  bool stopping_ = false;
  std::exception_ptr error_;
  std::thread thread_;
};

}  // namespace oefmt
