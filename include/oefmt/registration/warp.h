// SPDX-License-Identifier: GPL-3.0-or-later
// The similarity warp of the older frame onto the newer one, fused with the apodization window.
#pragma once

#include <opencv2/core.hpp>

#include "oefmt/registration/simd_kernel_choice.h"
#include "oefmt/registration/window.h"

namespace oefmt {

/// out(x) = window(x) * (bilinear(source, centre + R(-rotation)(x - centre) / zoom) - offset)
/// inside the source and 0 outside: source rotated counter-clockwise on screen by `rotation`
/// [rad] and zoomed by `zoom` about centre = (N/2, N/2), less its mean `offset`, then apodized.
/// One pass, no intermediate image.
void warpSimilarityWindowed(const cv::Mat1f& source, double rotation, double zoom,
                            const SeparableWindow& window, cv::Mat1f& out, float offset = 0.0f,
                            SimdKernel kernel = SimdKernel::kAuto);

}  // namespace oefmt
