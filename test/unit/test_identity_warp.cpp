// SPDX-License-Identifier: GPL-3.0-or-later
// registration.identity_warp_px: a rotation/zoom that moves no pixel noticeably correlates the
// older frame's cached spectrum without a warp; the result must be the warped one's.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "oefmt/error.h"
#include "oefmt/registration/registration.h"
#include "support/fixtures.h"

namespace oefmt {
namespace {

constexpr int kN = 256;

PairRegistration registerWith(double identity_warp_px, const cv::Mat& older, const cv::Mat& newer,
                              RegistrationMethod method = RegistrationMethod::kEnergyVectors) {
  RegistrationConfig config;
  config.size = kN;
  config.fft_planning = FftPlanning::kEstimate;
  config.identity_warp_px = identity_warp_px;
  Registrar registrar(config);
  return registrar.registerPair(registrar.analyse(older), registrar.analyse(newer), method);
}

TEST(IdentityWarp, ShiftsWithoutRotationOrZoomSkipTheWarpWithTheSameResult) {
  int skipped = 0;
  for (int i = 0; i < 6; ++i) {
    const double direction = 2.0 * CV_PI * (i + 0.2) / 6;
    const double length = 12.0 + 7.3 * i;
    sim::ViewMotion motion;
    motion.shift = {length * std::cos(direction), length * std::sin(direction)};
    const auto pair = test::warpedPair(motion, kN, 11);
    for (RegistrationMethod method :
         {RegistrationMethod::kEnergyVectors, RegistrationMethod::kClassic}) {
      // A whole pixel at the corners: every pair of pure shifts counts as the identity.
      const PairRegistration cached = registerWith(1.0, pair.older, pair.newer, method);
      const PairRegistration warped = registerWith(0.0, pair.older, pair.newer, method);
      ASSERT_EQ(cached.status, RegistrationStatus::kOk) << i;
      ASSERT_EQ(warped.status, RegistrationStatus::kOk) << i;
      EXPECT_FALSE(cached.warped) << i;
      EXPECT_TRUE(warped.warped) << i;
      skipped += cached.warped ? 0 : 1;
      EXPECT_NEAR(cached.translation.x, motion.shift.x, 0.2) << i;
      EXPECT_NEAR(cached.translation.y, motion.shift.y, 0.2) << i;
      EXPECT_NEAR(cached.translation.x, warped.translation.x, 0.05) << i;
      EXPECT_NEAR(cached.translation.y, warped.translation.y, 0.05) << i;
      EXPECT_NEAR(cached.shift_sigma, warped.shift_sigma, 0.05 * warped.shift_sigma) << i;
      EXPECT_NEAR(cached.confidence, warped.confidence, 0.05) << i;
      EXPECT_EQ(cached.half_turn, warped.half_turn) << i;
      ASSERT_EQ(cached.translation_energy.size(), warped.translation_energy.size());
      if (method == RegistrationMethod::kEnergyVectors) {
        EXPECT_EQ(test::argmax(cached.translation_energy), test::argmax(warped.translation_energy));
      }
    }
  }
  EXPECT_EQ(skipped, 12);
}

TEST(IdentityWarp, RotationsAndZoomsAreStillWarped) {
  sim::ViewMotion rotated;
  rotated.rotation = test::rad(1.0);  // 1.6 px at the corners of 256 x 256
  rotated.shift = {9.0, -4.0};
  sim::ViewMotion zoomed;
  zoomed.zoom = 1.01;  // 1.8 px at the corners
  zoomed.shift = {-6.0, 3.0};
  for (const sim::ViewMotion& motion : {rotated, zoomed}) {
    const auto pair = test::warpedPair(motion, kN, 11);
    const PairRegistration r = registerWith(0.1, pair.older, pair.newer);
    ASSERT_EQ(r.status, RegistrationStatus::kOk);
    EXPECT_TRUE(r.warped);
    EXPECT_NEAR(r.translation.x, motion.shift.x, 0.3);
    EXPECT_NEAR(r.translation.y, motion.shift.y, 0.3);
  }
  // The same image twice: nothing moves, nothing is warped.
  const auto still = test::warpedPair(sim::ViewMotion{}, kN, 11);
  EXPECT_FALSE(registerWith(0.1, still.older, still.older).warped);
}

TEST(IdentityWarp, OutOfRangeThresholdsAreRefused) {
  RegistrationConfig config;
  config.identity_warp_px = -0.1;
  EXPECT_THROW(config.validate(), InputError);
  config.identity_warp_px = 1.5;
  EXPECT_THROW(config.validate(), InputError);
  config.identity_warp_px = std::nan("");
  EXPECT_THROW(config.validate(), InputError);
}

}  // namespace
}  // namespace oefmt
