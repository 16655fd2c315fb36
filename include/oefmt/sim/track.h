// SPDX-License-Identifier: GPL-3.0-or-later
// Flight tracks flown at constant speed: circle, figure-8 and straight line.
#pragma once

#include <string>
#include <vector>

#include "oefmt/sim/camera_model.h"

namespace oefmt {
namespace sim {

enum class TrackShape {
  kCircle,  ///< counter-clockwise, centred on the origin, starting at (R, 0)
  kEight,   ///< figure-8 (lemniscate of Gerono) through the origin, lobes along x
  kLine,    ///< straight, from the origin along `line_direction`
};

enum class HeadingMode {
  kFixed,   ///< yaw stays at `yaw`
  kTrack,   ///< yaw follows the direction of motion, plus `yaw`
};

struct TrackConfig {
  TrackShape shape = TrackShape::kCircle;
  double length = 491.0;      ///< path length from the first to the last frame [m]
  int frames = 200;
  double altitude = 10.0;     ///< height above the ground at the start [m]
  /// Altitude change [m]: a line climbs linearly to altitude + climb; closed tracks climb to it
  /// half-way (smoothly, 1 - cos) and come back, so the loop still closes.
  double climb = 0.0;
  HeadingMode heading = HeadingMode::kFixed;
  double yaw = 0.0;             ///< [rad]
  double line_direction = 0.0;  ///< direction of a line track [rad] from +x, counter-clockwise

  /// Throws InputError naming the first invalid field.
  void validate() const;
};

/// True for tracks that end where they start (circle, eight): their last frame repeats the first,
/// as in the authors' datasets (N frames, N - 1 equal steps around the loop).
bool isClosed(TrackShape shape);

/// Distance between consecutive frames [m].
double frameSpacing(const TrackConfig& config);

/// The camera pose of every frame, at equal distances along the track.
std::vector<FlightPose> makeTrack(const TrackConfig& config);

/// "circle", "eight", "line" -> shape; throws InputError otherwise.
TrackShape trackShapeFromString(const std::string& name);
const char* toString(TrackShape shape);

}  // namespace sim
}  // namespace oefmt
