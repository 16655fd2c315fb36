// SPDX-License-Identifier: GPL-3.0-or-later
// What a ground plane that is not perpendicular to the view does to a pair's zoom, and how the
// pair's stretch tells the plane's tilt.
//
// A camera moving by t over a plane n.X = d (n its normal, in the camera's frame) sees the plane
// map from one frame to the next by H = I - t n^T / d. For a small tilt, H's linear part is
// (1 + t_z/d) I - u v^T with u = t_xy/d and v = n_xy: besides the zoom of the motion along the
// view, a rank-one term whose isotropic part (-u.v/2) the registration reads as zoom, and whose
// stretch along the motion (-|u| v_u / 2) tells the tilt. The distance along the view to the plane
// changes by n.t. In a levelled view off by an attitude error δ the ground is level and the view
// tilted: the altitude changes by n.t, the zoom that carries it is t_z/d + u.v, the read zoom plus
// 1.5 u.v, and flying L the read zoom is off by 1.5 δ L / d, a climb or descent that is not there.
// A level camera over a sloping surface sees the same images, but there t_z is the climb and n.t
// the surface's rise: the zoom that carries the altitude is the read zoom plus u.v / 2.
// The term's antisymmetric part, (u v^T - v u^T) / 2, is a turn of half the tilt across the
// motion: both views read it as one, though neither turned. Along a flight whose attitude error
// leans across the track it is the same every frame, and the heading drifts.
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

/// The change of rotation [rad] that a tilt [1/px] makes the registration miss on a pair that
/// moved by `translation` [px]: add it to the read rotation. The rank-one term's antisymmetric
/// part: half the tilt across the motion times the motion's length. A fit of the pair's linear
/// map (rotation, zoom and stretch: similarity_refinement.h) reads all of it into its rotation;
/// the log-polar surface reads the spectrum's angular shift, which the term's stretch spreads
/// over the directions, and locks part of it to the nearest bin.
double rotationOfTilt(const cv::Point2d& tilt, const cv::Point2d& translation);

/// rotationOfTilt of the tilt that a pair's stretch reads (tiltFromStretch): linear in the
/// stretch, so that its sigma follows from the fit's covariance.
double rotationOfSlope(double stretch_a, double stretch_b, const cv::Point2d& translation);

/// A level camera over a surface that slopes: the ln(zoom) to add to a pair's read zoom so that
/// it carries the camera's climb (t_z / d) and not the surface's rise under the motion. The read
/// zoom holds -u.v / 2, the isotropic part of the rank-one term, and the pair's stretch along its
/// motion the same -u.v / 2: the correction is minus that stretch, (tilt . d) / 2 with the tilt
/// the stretch reads (tiltFromStretch). Any depth structure under a translation bends the flow by
/// a term of that form (the flow is the translation times the inverse depth), so a surface's
/// slope, a layer's edge or a mixture of layers in the fitted pixels are corrected alike; a
/// climb and a turn stretch nothing.
double logZoomOfSlope(double stretch_a, double stretch_b, const cv::Point2d& translation);

}  // namespace oefmt
