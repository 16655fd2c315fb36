// SPDX-License-Identifier: GPL-3.0-or-later
// A bounded queue between ROS callbacks and the worker thread. With capacity 1 (the default) it
// is a mailbox where the newest item wins: the lowest latency for a live camera. A larger
// capacity absorbs processing hiccups (a bag replayed faster than real time) at the cost of
// latency. When full, the oldest waiting item is dropped (and counted by the caller). Never
// blocks the producer and never grows past its capacity.
#pragma once

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>
#include <utility>

namespace oefmt {

template <typename T>
class FrameQueue {
 public:
  explicit FrameQueue(std::size_t capacity = 1) : capacity_(capacity < 1 ? 1 : capacity) {}

  /// Sets how many items may wait; call before the consumer starts.
  void setCapacity(std::size_t capacity) {
    std::lock_guard<std::mutex> lock(mutex_);
    capacity_ = capacity < 1 ? 1 : capacity;
  }

  /// Stores `item`; returns true when the queue was full and its oldest item was dropped.
  bool put(T item) {
    bool dropped = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (items_.size() >= capacity_) {
        items_.pop_front();
        dropped = true;
      }
      items_.push_back(std::move(item));
    }
    ready_.notify_one();
    return dropped;
  }

  /// Waits for the oldest item; returns false once shutdown() was called.
  bool take(T& item) {
    std::unique_lock<std::mutex> lock(mutex_);
    ready_.wait(lock, [this] { return !items_.empty() || shutdown_; });
    if (shutdown_) return false;
    item = std::move(items_.front());
    items_.pop_front();
    return true;
  }

  /// Drops every waiting item (e.g. on reset).
  void clear() {
    std::lock_guard<std::mutex> lock(mutex_);
    items_.clear();
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
  std::deque<T> items_;
  std::size_t capacity_;
  bool shutdown_ = false;
};

}  // namespace oefmt
