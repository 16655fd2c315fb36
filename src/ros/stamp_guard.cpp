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

}  // namespace oefmt
