// SPDX-License-Identifier: GPL-3.0-or-later
// Private to src/estimation: one long-lived background thread for work that runs alongside the
// caller (the estimator's pair 0-2). A thread per task (std::async) cost every frame a thread
// start, a fresh stack and cold caches.
#pragma once

#include <condition_variable>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <thread>
#include <type_traits>
#include <utility>

namespace oefmt {
namespace detail {

/// Runs submitted tasks in order on one thread, started on the first task. The destructor
/// finishes the tasks already submitted, then joins. When no thread can be started, a task
/// runs on the caller instead (still through its future).
class WorkerThread {
 public:
  WorkerThread() = default;
  ~WorkerThread();
  WorkerThread(const WorkerThread&) = delete;
  WorkerThread& operator=(const WorkerThread&) = delete;

  /// The task's result (or exception) arrives through the future.
  template <typename Task>
  std::future<std::invoke_result_t<Task>> submit(Task&& task) {
    using Result = std::invoke_result_t<Task>;
    auto packaged = std::make_shared<std::packaged_task<Result()>>(std::forward<Task>(task));
    std::future<Result> result = packaged->get_future();
    post([packaged] { (*packaged)(); });
    return result;
  }

 private:
  void post(std::function<void()> task);
  void run();

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::function<void()>> tasks_;
  bool stopping_ = false;
  std::thread thread_;
};

}  // namespace detail
}  // namespace oefmt
