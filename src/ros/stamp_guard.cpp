// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/ros/stamp_guard.h"

#include <cmath>

namespace oefmt {

StampGuard::Verdict StampGuard::check(double stamp) {
  if (!std::isfinite(stamp)) return Verdict::kInvalid;
  if (!has_last_ || stamp > last_) {
    has_last_ = true;
    last_ = stamp;
    return Verdict::kAccept;
  }
  if (stamp == last_) return Verdict::kDuplicate;
  if (last_ - stamp <= tolerance_) return Verdict::kOutOfOrder;
  last_ = stamp;
  return Verdict::kJumpBack;
}

const char* toString(StampGuard::Verdict verdict) {
  switch (verdict) {
    case StampGuard::Verdict::kAccept: return "accepted";
    case StampGuard::Verdict::kDuplicate: return "duplicate stamp";
    case StampGuard::Verdict::kOutOfOrder: return "stamp older than the previous frame";
    case StampGuard::Verdict::kJumpBack: return "time jumped back";
    case StampGuard::Verdict::kInvalid: return "stamp is not finite";
  }
  return "unknown";
}

}  // namespace oefmt
