// SPDX-License-Identifier: GPL-3.0-or-later
// The estimator's background thread for pair 0-2: results and exceptions through the futures,
// tasks in order on one thread that is not the caller's, nothing dropped at destruction.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <stdexcept>
#include <thread>
#include <vector>

#include "estimation/worker_thread.h"

namespace oefmt {
namespace {

TEST(WorkerThread, RunsTasksInOrderOnOneOtherThread) {
  detail::WorkerThread worker;
  std::vector<int> order;  // only the worker writes it
  std::vector<std::future<std::thread::id>> ids;
  for (int i = 0; i < 20; ++i) {
    ids.push_back(worker.submit([&order, i] {
      order.push_back(i);
      return std::this_thread::get_id();
    }));
  }
  const std::thread::id first = ids.front().get();
  EXPECT_NE(first, std::this_thread::get_id());
  for (std::size_t i = 1; i < ids.size(); ++i) EXPECT_EQ(ids[i].get(), first);
  ASSERT_EQ(order.size(), 20u);
  for (int i = 0; i < 20; ++i) EXPECT_EQ(order[i], i);
}

TEST(WorkerThread, AnExceptionReachesTheFutureAndTheThreadGoesOn) {
  detail::WorkerThread worker;
  std::future<int> failing = worker.submit([]() -> int { throw std::runtime_error("no overlap"); });
  EXPECT_THROW(failing.get(), std::runtime_error);
  EXPECT_EQ(worker.submit([] { return 7; }).get(), 7);
}

TEST(WorkerThread, DestructionFinishesTheSubmittedTasks) {
  std::atomic<int> done{0};
  {
    detail::WorkerThread worker;
    for (int i = 0; i < 5; ++i) {
      worker.submit([&done] {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        ++done;
      });
    }
  }
  EXPECT_EQ(done.load(), 5);
}

}  // namespace
}  // namespace oefmt
