// SPDX-License-Identifier: GPL-3.0-or-later
// The followed layer's length against the depth layers in view, remembered over the last frames.
//
// The length of a step (the followed layer's shift) over the shift of another depth layer in the
// same pair is the ratio of their depths: it does not depend on the vehicle's speed, and it
// changes only as slowly as the altitude. A step whose length breaks every ratio the layers in
// view have held over the last frames did not come from a change of motion: one wrong pattern
// match or loop (a layer taken for another, a periodic texture's alias) shortened or stretched
// it, and every later step, measured against it, would keep that wrong scale. The remembered
// ratios give the length the layers in view vouch for instead.
#pragma once

#include <deque>
#include <optional>
#include <vector>

namespace oefmt {

class LayerRatioMemory {
 public:
  /// frames: how many of the last steps are remembered; support: in how many of them a ratio must
  /// have held (to within `tolerance`, relative) to vouch for a length.
  LayerRatioMemory(int frames, int support, double tolerance);

  /// Remembers an accepted step's length against the shifts of the layers in its pair (its
  /// translation energy peaks) [px].
  void remember(double length, const std::vector<double>& layer_shifts);

  /// The length the remembered ratios give for a pair whose layers shift by `layer_shifts` [px]:
  /// the one that the most ratio-layer pairs give (to within the tolerance), of several such the
  /// one nearest `steady` (the length the motion so far predicts). Nothing when no ratio of the
  /// newest step has held long enough: a step that broke the ratios silences the memory until
  /// its own ratios have held as long, so that it never fights a new scale it cannot mend.
  std::optional<double> vouchedLength(const std::vector<double>& layer_shifts, double steady) const;
  /// vouchedLength with the number of ratio-layer pairs that give it.
  struct Vouched {
    double length = 0.0;  ///< [px]
    int votes = 0;
  };
  std::optional<Vouched> vouch(const std::vector<double>& layer_shifts, double steady) const;

  void clear() { frames_.clear(); }

 private:
  // The newest step's ratios that held in `support` of the remembered steps, each the median of
  // its matches.
  std::vector<double> heldRatios() const;

  int frames_kept_;
  int support_;
  double tolerance_;
  std::deque<std::vector<double>> frames_;  // per remembered step: length / layer shift
};

}  // namespace oefmt
