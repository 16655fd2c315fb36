// SPDX-License-Identifier: GPL-3.0-or-later
// What a ground plane that is not perpendicular to the view does to a pair's zoom, and how the
// pair's stretch tells the plane's tilt.
//
// A camera moving by t over a plane n.X = d (n its normal, in the camera's frame) sees the plane
// map from one frame to the next by H = I - t n^T / d. For a small tilt, H's linear part is
// (1 + t_z/d) I - u v^T with u = t_xy/d and v = n_xy: besides the zoom of the motion along the
// view, a rank-one term whose isotropic part (-u.v/2) the registration reads as zoom, and whose
// stretch along the motion (-|u| v_u / 2) tells the tilt. The distance along the view to the plane
// changes by n.t, so the zoom that carries the altitude is t_z/d + u.v: the read zoom plus 1.5 u.v.
// A level camera over a slope and a levelled view off by an attitude error δ are the same case (a
// tilt δ): flying L, the read zoom is off by 1.5 δ L / d, a climb or descent that is not there.
//
// In pixels the tilt is v / f [1/px]: a pair that moved by d [px] is stretched along d by
// -(tilt . d) / 2 (the stretch of S = [a b; b -a] along a unit vector w is w^T S w), and its read
// ln(zoom) misses 1.5 (tilt . d), three times the opposite of that stretch.
#pragma once

#include <opencv2/core/types.hpp>

namespace oefmt {

/// The plane's tilt v / f [1/px] (image axes: x right, y down) that one pair's area-preserving
/// stretch S = [a b; b -a] and translation d [px] read (zero when d is).
cv::Point2d tiltFromStretch(double stretch_a, double stretch_b, const cv::Point2d& translation);

/// The change of ln(zoom) that a tilt [1/px] makes the registration miss on a pair that moved by
/// `translation` [px]: add it to the read ln(zoom).
double logZoomOfTilt(const cv::Point2d& tilt, const cv::Point2d& translation);

}  // namespace oefmt
