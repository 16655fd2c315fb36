// SPDX-License-Identifier: GPL-3.0-or-later
// The simulated vehicle's IMU and downward rangefinder, with the errors real ones have.
#pragma once

#include <cstdint>
#include <vector>

#include "oefmt/io/vehicle_data.h"
#include "oefmt/sim/scene.h"
#include "oefmt/sim/vehicle_motion.h"

namespace oefmt {
namespace sim {

struct ImuOptions {
  double rate = 200.0;             ///< samples per second [Hz]
  double gyro_noise = 0.003;       ///< white noise of each angular-velocity sample [rad/s]
  double gyro_bias = 0.005;        ///< constant bias of each gyro axis, drawn in [-b, b] [rad/s]
  double accel_noise = 0.05;       ///< white noise of each specific-force sample [m/s^2]
  /// An attitude filter's error: a slow wander of roll and pitch within this amplitude [rad]
  /// (periods of tens of seconds), plus white noise of orientation_noise [rad] per sample.
  double attitude_error = 0.3 * CV_PI / 180.0;
  double orientation_noise = 0.02 * CV_PI / 180.0;
  /// Throws InputError naming the first invalid field.
  void validate() const;
};

struct RangeOptions {
  double noise = 0.03;      ///< white noise of each range [m]
  double dropout = 0.02;    ///< probability of a reading without return (+inf)
  double max_range = 60.0;  ///< beyond it: no return (+inf) [m]
  /// Throws InputError naming the first invalid field.
  void validate() const;
};

/// IMU samples from t0 to t1 (the IMU frame is the body frame). Deterministic for `seed`.
std::vector<ImuSample> simulateImu(const VehicleMotion& motion, double t0, double t1, const ImuOptions& options,
                                   std::uint32_t seed);

/// The rangefinder's reading from `pose`: the distance along the body's -z axis to the first
/// surface of `scene` (a roof when over one), with noise and dropouts (deterministic for seed and
/// sample index).
double simulateRange(const Scene& scene, const FlightPose& pose, const RangeOptions& options, std::uint32_t seed,
                     int index);

}  // namespace sim
}  // namespace oefmt
