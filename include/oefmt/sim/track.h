// SPDX-License-Identifier: GPL-3.0-or-later
// Flight tracks flown at constant speed: circle, figure-8 and straight line; and a turn on the
// spot.
#pragma once

#include <memory>
#include <string>
#include <vector>

#include "oefmt/enum_names.h"
#include "oefmt/sim/camera_model.h"

namespace oefmt {
namespace sim {

enum class TrackShape {
  kCircle,  ///< counter-clockwise, centred on the origin, starting at (R, 0)
  kEight,   ///< figure-8 (lemniscate of Gerono) through the origin, lobes along x
  kLine,    ///< straight, from the origin along `line_direction`
  kSpin,    ///< no motion: at the origin, the yaw turning by `spin_rate` per frame
};

/// How the altitude changes by `climb` along a track.
enum class ClimbProfile {
  kAuto,  ///< kRamp for a line, kHill for loops (which must come back)
  kRamp,  ///< linearly from altitude to altitude + climb (lines only)
  kHill,  ///< smoothly (1 - cos) to altitude + climb half-way and back to altitude
};

enum class HeadingMode {
  kFixed,   ///< yaw stays at `yaw`
  kTrack,   ///< yaw follows the direction of motion, plus `yaw`
};

struct TrackConfig {
  TrackShape shape = TrackShape::kCircle;
  double length = 491.0;      ///< path length from the first to the last frame [m] (not kSpin)
  int frames = 200;
  double altitude = 10.0;     ///< height above the ground at the start [m]
  /// Altitude change [m] (negative: a descent), shaped by climb_profile: by default a line climbs
  /// linearly to altitude + climb; closed tracks climb to it half-way (smoothly, 1 - cos) and come
  /// back, so the loop still closes. A spin has none.
  double climb = 0.0;
  ClimbProfile climb_profile = ClimbProfile::kAuto;
  HeadingMode heading = HeadingMode::kFixed;  ///< kTrack needs a moving track (not kSpin)
  double yaw = 0.0;             ///< [rad]; a spin's yaw at the first frame
  double line_direction = 0.0;  ///< direction of a line track [rad] from +x, counter-clockwise
  double spin_rate = 6.0 * CV_PI / 180.0;  ///< yaw change per frame of a spin [rad], either sign

  /// Throws InputError naming the first invalid field.
  void validate() const;
};

/// True for tracks that end where they start (circle, eight): their last frame repeats the first,
/// as in the authors' datasets (N frames, N - 1 equal steps around the loop).
bool isClosed(TrackShape shape);

/// True for tracks along which the camera moves (all but kSpin).
bool isMoving(TrackShape shape);

/// The climb profile that applies (kAuto resolved).
ClimbProfile resolvedClimbProfile(const TrackConfig& config);

/// Distance between consecutive frames [m] (0 for a spin).
double frameSpacing(const TrackConfig& config);

struct ArcTable;

/// The track as a function of a continuous frame position k (frame k at k = 0, 1, ...; between
/// and beyond them the same constant-speed motion: loops repeat, lines go on straight, a spin
/// keeps turning). Level poses.
class TrackPath {
 public:
  /// Throws InputError naming the first invalid field of `config`.
  explicit TrackPath(const TrackConfig& config);
  FlightPose at(double k) const;
  const TrackConfig& config() const { return config_; }

 private:
  TrackConfig config_;
  std::shared_ptr<const ArcTable> table_;  // arc length of the unit shape (moving tracks)
  double scale_ = 1.0;                     // metres per unit of the shape
};

/// The camera pose of every frame, at equal distances along the track.
std::vector<FlightPose> makeTrack(const TrackConfig& config);

/// The command line's spelling of each shape, profile and heading mode (parseEnum reads it).
inline constexpr EnumName<TrackShape> kTrackShapeNames[] = {
    {TrackShape::kCircle, "circle"}, {TrackShape::kEight, "eight"}, {TrackShape::kLine, "line"},
    {TrackShape::kSpin, "spin"}};
inline const char* toString(TrackShape shape) { return enumName(kTrackShapeNames, shape); }
inline constexpr EnumName<ClimbProfile> kClimbProfileNames[] = {
    {ClimbProfile::kRamp, "ramp"}, {ClimbProfile::kHill, "hill"}};
inline constexpr EnumName<HeadingMode> kHeadingModeNames[] = {
    {HeadingMode::kFixed, "fixed"}, {HeadingMode::kTrack, "track"}};

}  // namespace sim
}  // namespace oefmt
