// SPDX-License-Identifier: GPL-3.0-or-later
#include "worker_thread.h"

#include <system_error>

namespace oefmt {
namespace detail {

WorkerThread::~WorkerThread() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stopping_ = true;
  }
  wake_.notify_one();
  if (thread_.joinable()) thread_.join();
}

void WorkerThread::post(std::function<void()> task) {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    if (!thread_.joinable()) {
      try {
        thread_ = std::thread(&WorkerThread::run, this);
      } catch (const std::system_error&) {
        // No thread to be had (a process at its limit): the caller runs the task.
      }
    }
    if (thread_.joinable()) {
      tasks_.push_back(std::move(task));
      task = nullptr;
    }
  }
  if (task) {
    task();
  } else {
    wake_.notify_one();
  }
}

void WorkerThread::run() {
  for (;;) {
    std::function<void()> task;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      wake_.wait(lock, [this] { return stopping_ || !tasks_.empty(); });
      if (tasks_.empty()) return;  // stopping, and nothing left to do
      task = std::move(tasks_.front());
      tasks_.pop_front();
    }
    task();  // a packaged task: its exceptions go to its future
  }
}

}  // namespace detail
}  // namespace oefmt
