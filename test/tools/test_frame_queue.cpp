// SPDX-License-Identifier: GPL-3.0-or-later
// The node's queue between callbacks and worker: newest wins at capacity 1, first in first out
// above, the oldest dropped when full, and shutdown releases a waiting worker.
#include <gtest/gtest.h>

#include <thread>

#include "oefmt/ros/frame_queue.h"

namespace oefmt {
namespace {

TEST(FrameQueue, CapacityOneKeepsTheNewest) {
  FrameQueue<int> queue;
  EXPECT_FALSE(queue.put(1));
  EXPECT_TRUE(queue.put(2)) << "1 was waiting: dropped";
  int item = 0;
  ASSERT_TRUE(queue.take(item));
  EXPECT_EQ(item, 2);
}

TEST(FrameQueue, LargerCapacityIsFirstInFirstOutAndDropsTheOldest) {
  FrameQueue<int> queue(3);
  for (int i = 1; i <= 3; ++i) EXPECT_FALSE(queue.put(i));
  EXPECT_TRUE(queue.put(4));
  int item = 0;
  for (int expected : {2, 3, 4}) {
    ASSERT_TRUE(queue.take(item));
    EXPECT_EQ(item, expected);
  }
  queue.put(5);
  queue.clear();
  queue.put(6);
  ASSERT_TRUE(queue.take(item));
  EXPECT_EQ(item, 6);
}

TEST(FrameQueue, ShutdownReleasesAWaitingConsumer) {
  FrameQueue<int> queue(2);
  bool result = true;
  std::thread consumer([&] {
    int item = 0;
    result = queue.take(item);
  });
  queue.shutdown();
  consumer.join();
  EXPECT_FALSE(result);
}

}  // namespace
}  // namespace oefmt
