// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <limits>

#include "oefmt/ros/stamp_guard.h"

namespace oefmt {
namespace {

using Verdict = StampGuard::Verdict;

TEST(StampGuard, AcceptsIncreasingStamps) {
  StampGuard guard(1.0);
  EXPECT_EQ(guard.check(10.0), Verdict::kAccept);
  EXPECT_EQ(guard.check(10.1), Verdict::kAccept);
  EXPECT_DOUBLE_EQ(guard.last(), 10.1);
}

TEST(StampGuard, DropsDuplicatesAndReorderings) {
  StampGuard guard(1.0);
  guard.check(10.0);
  EXPECT_EQ(guard.check(10.0), Verdict::kDuplicate);
  EXPECT_EQ(guard.check(9.5), Verdict::kOutOfOrder);
  EXPECT_DOUBLE_EQ(guard.last(), 10.0);  // a dropped stamp does not move the reference
  EXPECT_EQ(guard.check(10.2), Verdict::kAccept);
}

TEST(StampGuard, LargeStepBackAsksForAReset) {
  StampGuard guard(1.0);
  guard.check(100.0);
  EXPECT_EQ(guard.check(3.0), Verdict::kJumpBack);
  EXPECT_EQ(guard.check(3.1), Verdict::kAccept);  // the new timeline continues
}

TEST(StampGuard, RejectsNonFiniteStamps) {
  StampGuard guard;
  EXPECT_EQ(guard.check(std::numeric_limits<double>::quiet_NaN()), Verdict::kInvalid);
  EXPECT_EQ(guard.check(std::numeric_limits<double>::infinity()), Verdict::kInvalid);
  EXPECT_FALSE(guard.hasLast());
}

}  // namespace
}  // namespace oefmt
