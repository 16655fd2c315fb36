// SPDX-License-Identifier: GPL-3.0-or-later
// A one-element mailbox between ROS callbacks and the worker thread: the newest item wins, an
// unprocessed older one is dropped (and counted by the caller). Never blocks the producer and
// never grows: no unbounded queue anywhere.
#pragma once

#include <condition_variable>
#include <mutex>
#include <optional>
#include <utility>

namespace oefmt {

template <typename T>
class LatestSlot {
 public:
  /// Stores `item`; returns true when it replaced an item the consumer had not taken (a drop).
  bool put(T item) {
    bool dropped = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      dropped = item_.has_value();
      item_ = std::move(item);
    }
    ready_.notify_one();
    return dropped;
  }

  /// Waits for an item; returns false once shutdown() was called.
  bool take(T& item) {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait(lock, [this] { return item_.has_value() || shutdown_; });
    if (shutdown_) return false;
    item = std::move(*item_);
    item_.reset();
    return true;
  }

  /// Drops a waiting item (e.g. on reset).
  void clear() {
    std::lock_guard<std::mutex> lock(mutex_);
    item_.reset();
  }

  void shutdown() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      shutdown_ = true;
    }
    ready_.notify_all();
  }

 private:
  std::mutex mutex_;
  std::condition_variable ready_;
  std::optional<T> item_;
  bool shutdown_ = false;
};

}  // namespace oefmt
