// SPDX-License-Identifier: GPL-3.0-or-later
// Judges each frame's time stamp against the last accepted one: duplicates and small reorderings
// are dropped, a large step back (a bag that loops, a restarted recording) asks for a reset.
#pragma once

#include "oefmt/enum_names.h"

namespace oefmt {

class StampGuard {
 public:
  enum class Verdict {
    kAccept,      ///< newer than the last accepted stamp
    kDuplicate,   ///< equal to the last accepted stamp: drop
    kOutOfOrder,  ///< older, by less than the jump tolerance: drop
    kJumpBack,    ///< older by more than the tolerance: reset, then accept as a first frame
    kInvalid,     ///< not finite: drop
  };

  /// jump_back_tolerance [s]: how far back a stamp may go and still count as a reordering.
  explicit StampGuard(double jump_back_tolerance = 1.0) : tolerance_(jump_back_tolerance) {}

  /// Judges `stamp` and, for kAccept and kJumpBack, makes it the last accepted stamp.
  Verdict check(double stamp);
  void reset() { has_last_ = false; }
  bool hasLast() const { return has_last_; }
  double last() const { return last_; }

 private:
  double tolerance_;
  bool has_last_ = false;
  double last_ = 0.0;
};

/// What each verdict means, for messages.
inline constexpr EnumName<StampGuard::Verdict> kStampVerdictNames[] = {
    {StampGuard::Verdict::kAccept, "accepted"},
    {StampGuard::Verdict::kDuplicate, "duplicate stamp"},
    {StampGuard::Verdict::kOutOfOrder, "stamp older than the previous frame"},
    {StampGuard::Verdict::kJumpBack, "time jumped back"},
    {StampGuard::Verdict::kInvalid, "stamp is not finite"}};
inline const char* toString(StampGuard::Verdict verdict) { return enumName(kStampVerdictNames, verdict); }

}  // namespace oefmt
