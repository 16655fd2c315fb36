// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/estimation/layer_ratio_memory.h"

#include <algorithm>
#include <cmath>

#include "oefmt/error.h"

namespace oefmt {
namespace {

bool near(double a, double b, double tolerance) { return std::fabs(a - b) <= tolerance * b; }

}  // namespace

LayerRatioMemory::LayerRatioMemory(int frames, int support, double tolerance)
    : frames_kept_(frames), support_(support), tolerance_(tolerance) {
  if (frames < 1 || support < 1 || support > frames || !(tolerance > 0.0 && tolerance < 1.0)) {
    throw InputError("layer ratio memory: needs 1 <= support <= frames and a tolerance in (0, 1)");
  }
}

void LayerRatioMemory::remember(double length, const std::vector<double>& layer_shifts) {
  std::vector<double> ratios;
  if (length > 0.0 && std::isfinite(length)) {
    for (double shift : layer_shifts) {
      if (shift > 0.0 && std::isfinite(shift)) ratios.push_back(length / shift);
    }
  }
  frames_.push_back(std::move(ratios));
  while (static_cast<int>(frames_.size()) > frames_kept_) frames_.pop_front();
}

std::vector<double> LayerRatioMemory::heldRatios() const {
  std::vector<double> held;
  if (static_cast<int>(frames_.size()) < support_) return held;
  for (double ratio : frames_.back()) {
    // A ratio of the newest step, matched in each older one by its nearest ratio.
    std::vector<double> matches{ratio};
    for (std::size_t k = 0; k + 1 < frames_.size(); ++k) {
      double best = 0.0;
      for (double r : frames_[k]) {
        if (near(r, ratio, tolerance_) && (best == 0.0 || std::fabs(r - ratio) < std::fabs(best - ratio))) best = r;
      }
      if (best > 0.0) matches.push_back(best);
    }
    if (static_cast<int>(matches.size()) < support_) continue;
    const auto middle = matches.begin() + static_cast<std::ptrdiff_t>(matches.size() / 2);
    std::nth_element(matches.begin(), middle, matches.end());
    held.push_back(*middle);
  }
  return held;
}

std::optional<double> LayerRatioMemory::vouchedLength(const std::vector<double>& layer_shifts,
                                                      double steady) const {
  const std::optional<Vouched> vouched = vouch(layer_shifts, steady);
  if (!vouched) return std::nullopt;
  return vouched->length;
}

std::optional<LayerRatioMemory::Vouched> LayerRatioMemory::vouch(const std::vector<double>& layer_shifts,
                                                                 double steady) const {
  const std::vector<double> ratios = heldRatios();
  std::vector<double> lengths;
  for (double ratio : ratios) {
    for (double shift : layer_shifts) {
      if (shift > 0.0 && std::isfinite(shift)) lengths.push_back(ratio * shift);
    }
  }
  // Each length's votes: the ratio-layer pairs that give it; a wrong pairing gives a length of
  // its own, the right ones agree. Of the lengths with the most votes, the one nearest `steady`
  // (with one layer in view, its ratios give as many lengths, one vote each).
  std::optional<Vouched> best;
  std::vector<bool> counted(lengths.size(), false);
  for (std::size_t i = 0; i < lengths.size(); ++i) {
    if (counted[i]) continue;
    int votes = 0;
    double sum = 0.0;
    for (std::size_t j = i; j < lengths.size(); ++j) {
      if (!counted[j] && near(lengths[j], lengths[i], tolerance_)) {
        ++votes;
        sum += lengths[j];
        counted[j] = true;
      }
    }
    const double length = sum / votes;
    if (!best || votes > best->votes ||
        (votes == best->votes && std::fabs(length - steady) < std::fabs(best->length - steady))) {
      best = Vouched{length, votes};
    }
  }
  return best;
}

}  // namespace oefmt
