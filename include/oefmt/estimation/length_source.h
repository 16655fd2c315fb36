// SPDX-License-Identifier: GPL-3.0-or-later
// Where the length of an integrated step came from. A step's direction is read well by every
// registration; its length is the followed depth layer's shift, and which reading gave it (the
// translation peak, another layer through a ratio, the pattern match, the motion so far, ...)
// is what tells a change of scale from a change of speed when a flight is looked at afterwards.
#pragma once

#include "oefmt/enum_names.h"

namespace oefmt {

enum class LengthSource {
  kNone,          ///< no step was integrated (the first frame, a predicted or held frame)
  kPeak,          ///< the pair's translation peak (the followed layer's, or the taken one without a prediction)
  kWindowPeak,    ///< the peak where the prediction pointed; another layer's peak was higher
  kEnergyPeak,    ///< the followed layer's peak in the translation energy vector
  kLayerRatio,    ///< a layer seen in both pairs, through its ratio to the previous pair's
  kStretch,       ///< the translation energy vectors' stretch against the previous pair's (PMT)
  kPrediction,    ///< the length the motion so far predicts: nothing in view read the followed layer
  kMotionChange,  ///< a peak on the motion within the acceleration window: the speed changed
  kLoop,          ///< the three-frame loop moved the length by more than the layer gate
  kVouched,       ///< the ratios the layers in view held over the last steps (LayerRatioMemory)
  kImplausible,   ///< the reading lay beyond the acceleration window: the predicted step stands
};
inline constexpr EnumName<LengthSource> kLengthSourceNames[] = {
    {LengthSource::kNone, "none"},
    {LengthSource::kPeak, "peak"},
    {LengthSource::kWindowPeak, "window_peak"},
    {LengthSource::kEnergyPeak, "energy_peak"},
    {LengthSource::kLayerRatio, "layer_ratio"},
    {LengthSource::kStretch, "stretch"},
    {LengthSource::kPrediction, "prediction"},
    {LengthSource::kMotionChange, "motion_change"},
    {LengthSource::kLoop, "loop"},
    {LengthSource::kVouched, "vouched"},
    {LengthSource::kImplausible, "implausible"}};
inline const char* toString(LengthSource source) { return enumName(kLengthSourceNames, source); }

}  // namespace oefmt
