// SPDX-License-Identifier: GPL-3.0-or-later
// The similarity warp of the older frame onto the newer one, fused with the apodization window.
#pragma once

#include <opencv2/core.hpp>

#include "oefmt/registration/simd_kernel_choice.h"
#include "oefmt/registration/window.h"

namespace oefmt {

/// The point an N x N frame turns and zooms about: its middle, (N - 1) / 2 in pixel indices
/// (pixel i covers [i - 1/2, i + 1/2]). It is where the principal point of the working frame lies
/// (the undistorter, the nadir view and the simulator put it there), so that a camera that only
/// yaws gives no translation; N / 2 would read every yaw of theta as a shift of about
/// 0.7 theta px.
inline double imageCentre(int n) { return (n - 1) / 2.0; }

/// out(x) = window(x) * (bilinear(source, centre + R(-rotation)(x - centre) / zoom) - offset)
/// inside the source and 0 outside: source rotated counter-clockwise on screen by `rotation`
/// [rad] and zoomed by `zoom` about centre = imageCentre(N), less its mean `offset`, then apodized.
/// One pass, no intermediate image.
void warpSimilarityWindowed(const cv::Mat1f& source, double rotation, double zoom,
                            const SeparableWindow& window, cv::Mat1f& out, float offset = 0.0f,
                            SimdKernel kernel = SimdKernel::kAuto);

}  // namespace oefmt
