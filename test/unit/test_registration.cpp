// SPDX-License-Identifier: GPL-3.0-or-later
// Invariants of the pair registration (doc/method.md, What the unit tests check).
#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"
#include "oefmt/registration/image_prep.h"
#include "oefmt/registration/registration.h"
#include "oefmt/registration/spectra.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/renderer.h"
#include "oefmt/sim/texture.h"
#include "support/fixtures.h"

namespace oefmt {
namespace {

using test::deg;
using test::rad;

constexpr int kN = 512;

void expectFiniteSigmas(const PairRegistration& r) {
  EXPECT_TRUE(std::isfinite(r.rotation_sigma));
  EXPECT_TRUE(std::isfinite(r.log_zoom_sigma));
  EXPECT_TRUE(std::isfinite(r.direction_sigma));
  EXPECT_TRUE(std::isfinite(r.shift_sigma));
  EXPECT_GT(r.rotation_sigma, 0.0);
  EXPECT_GT(r.shift_sigma, 0.0);
}

TEST(Registration, IdentityGivesNoMotion) {
  const auto pair = test::warpedPair(sim::ViewMotion{});
  const PairRegistration r = test::registerImages(pair.older, pair.older);
  EXPECT_EQ(r.status, RegistrationStatus::kOk);
  EXPECT_NEAR(deg(r.rotation), 0.0, 0.05);
  EXPECT_NEAR(r.zoom, 1.0, 0.002);
  EXPECT_LT(r.shift, 0.1);
  EXPECT_EQ(test::argmax(r.translation_energy), 0);
  EXPECT_EQ(test::argmax(r.zoom_energy), kN / 2);
  EXPECT_FALSE(r.half_turn);
  EXPECT_GT(r.confidence, 0.9);
  expectFiniteSigmas(r);
}

struct ShiftCase {
  double tx, ty;
};
class PureShift : public ::testing::TestWithParam<ShiftCase> {};

TEST_P(PureShift, SubPixelAccurate) {
  const ShiftCase c = GetParam();
  sim::ViewMotion motion;
  motion.shift = {c.tx, c.ty};
  const auto pair = test::warpedPair(motion);
  const PairRegistration r = test::registerImages(pair.older, pair.newer);
  ASSERT_EQ(r.status, RegistrationStatus::kOk);
  EXPECT_NEAR(r.translation.x, c.tx, 0.2);
  EXPECT_NEAR(r.translation.y, c.ty, 0.2);
  EXPECT_NEAR(deg(r.rotation), 0.0, 0.05);
  EXPECT_NEAR(r.zoom, 1.0, 0.002);
  const double length = std::hypot(c.tx, c.ty);
  if (length > 1.0) {
    EXPECT_NEAR(std::remainder(r.direction - std::atan2(c.ty, c.tx), 2 * CV_PI), 0.0, 0.02);
    EXPECT_NEAR(test::argmax(r.translation_energy), std::round(length / 0.75), 1.0);
  }
  expectFiniteSigmas(r);
}

INSTANTIATE_TEST_SUITE_P(Shifts, PureShift,
                         ::testing::Values(ShiftCase{0.3, -0.2}, ShiftCase{5.25, -2.75},
                                           ShiftCase{-17.4, 11.6}, ShiftCase{30.0, 0.0},
                                           ShiftCase{28.5, -0.3}, ShiftCase{0.4, 39.6},
                                           ShiftCase{-25.7, -28.1}, ShiftCase{-38.0, 0.2}));

// Consecutive frames of a flight are shifted by 60-100 px with no rotation or zoom: whole-bin
// offsets on the log-polar surface, where a refinement that jumps between the peak's sides would
// add +-0.05 deg and +-5e-4 of ln zoom of noise to every frame (the heading and altitude drift).
// The peak's neighbours are then only 1-3 % of it and partly noise (they differ between
// compilers by that much), so single zooms are bounded at the noise level (0.036 bin) and the
// bias by the mean (the larger-neighbour ratio: 0.0165 deg, mean -2.0e-4).
TEST(Registration, FlightSizedShiftsLeaveRotationAndZoomAtZero) {
  double log_zoom_sum = 0.0;
  constexpr int kDirections = 8;
  for (int i = 0; i < kDirections; ++i) {
    const double direction = 2.0 * CV_PI * (i + 0.3) / kDirections;
    const double length = 60.0 + 5.0 * i;
    sim::ViewMotion motion;
    motion.shift = {length * std::cos(direction), length * std::sin(direction)};
    const auto pair = test::warpedPair(motion);
    const PairRegistration r = test::registerImages(pair.older, pair.newer);
    ASSERT_EQ(r.status, RegistrationStatus::kOk);
    EXPECT_NEAR(deg(r.rotation), 0.0, 0.01) << "shift " << motion.shift;
    EXPECT_NEAR(std::log(r.zoom), 0.0, 4e-4) << "shift " << motion.shift;
    log_zoom_sum += std::log(r.zoom);
  }
  EXPECT_NEAR(log_zoom_sum / kDirections, 0.0, 1.5e-4);
}

TEST(Registration, AShiftBeyondThePolarUnwrapsReachKeepsTheEnergyVectorOnItsDirection) {
  // polar_radius_fraction 0.25 unwraps radii up to 128 px; the shift is 150 px.
  RegistrationConfig config;
  config.size = kN;
  config.polar_radius_fraction = 0.25;
  config.fft_planning = FftPlanning::kEstimate;  // a context of its own: no planning wait
  Registrar registrar(std::make_shared<const SpectralContext>(config));
  const double direction = rad(35.0);
  sim::ViewMotion motion;
  motion.shift = {150.0 * std::cos(direction), 150.0 * std::sin(direction)};
  const auto pair = test::warpedPair(motion);
  const PairRegistration r =
      registrar.registerPair(registrar.analyse(pair.older), registrar.analyse(pair.newer));
  ASSERT_EQ(r.status, RegistrationStatus::kOk);
  EXPECT_NEAR(r.translation.x, motion.shift.x, 0.3);
  EXPECT_NEAR(r.translation.y, motion.shift.y, 0.3);
  ASSERT_EQ(static_cast<int>(r.translation_energy.size()), kN);
  EXPECT_TRUE(std::isfinite(r.direction_sigma));
  EXPECT_TRUE(std::isfinite(r.shift_sigma));
  EXPECT_NEAR(r.direction, direction, 0.02);
}

class PureRotation : public ::testing::TestWithParam<double> {};

TEST_P(PureRotation, AngleWithinFiveHundredthsOfADegree) {
  const double degrees = GetParam();
  sim::ViewMotion motion;
  motion.rotation = rad(degrees);
  const auto pair = test::warpedPair(motion);
  const PairRegistration r = test::registerImages(pair.older, pair.newer);
  ASSERT_EQ(r.status, RegistrationStatus::kOk);
  EXPECT_NEAR(std::remainder(deg(r.rotation) - degrees, 360.0), 0.0, 0.05);
  EXPECT_NEAR(r.zoom, 1.0, 0.002);
  EXPECT_LT(r.shift, 0.3);
  EXPECT_EQ(r.half_turn, std::fabs(degrees) > 90.0);
  expectFiniteSigmas(r);
}

// Beyond +-90 degrees the log-polar spectrum is ambiguous by a half turn; the translation peak
// resolves it.
INSTANTIATE_TEST_SUITE_P(Rotations, PureRotation,
                         ::testing::Values(1.3, -4.0, 10.6, -27.0, 45.0, -62.5, 85.0, 120.0,
                                           -135.0, 170.0, -178.0));

// A camera that only yaws turns its view about the principal point, which the simulator (like
// the undistorter) puts at the middle of the image, (N - 1) / 2. Registered about any other
// point, every yaw of theta would read as a shift of theta times the distance between the two
// (0.19 px at 15 degrees for a point half a pixel off in x and y), which a yawing flight
// integrates into a sideways drift.
TEST(Registration, AYawAboutThePrincipalPointGivesNoShift) {
  sim::FlightOptions options;
  options.width = options.height = 256;
  options.track.shape = sim::TrackShape::kSpin;
  options.track.frames = 4;
  options.track.spin_rate = rad(-15.0);
  options.flat = true;
  options.texture_size = 1024;
  options.seed = 23;
  const sim::FlightPlan plan = sim::planFlight(options);
  const sim::Renderer renderer(std::make_shared<const sim::Scene>(plan.scene), plan.camera, plan.supersample);
  cv::Mat1f older = renderer.render(plan.poses[0]).image;
  for (std::size_t k = 1; k < plan.poses.size(); ++k) {
    const cv::Mat1f newer = renderer.render(plan.poses[k]).image;
    const PairRegistration r = test::registerImages(older, newer);
    ASSERT_EQ(r.status, RegistrationStatus::kOk) << k;
    EXPECT_NEAR(std::fabs(deg(r.rotation)), 15.0, 0.05) << k;
    EXPECT_LT(r.shift, 0.05) << k << ": " << r.translation;
    older = newer;
  }
}

class PureZoom : public ::testing::TestWithParam<double> {};

TEST_P(PureZoom, ScaleWithinTwoTenthsOfAPercent) {
  const double zoom = GetParam();
  sim::ViewMotion motion;
  motion.zoom = zoom;
  const auto pair = test::warpedPair(motion);
  Registrar registrar(test::sharedContext(kN));
  const PairRegistration r = test::registerImages(pair.older, pair.newer);
  ASSERT_EQ(r.status, RegistrationStatus::kOk);
  EXPECT_NEAR(r.zoom / zoom, 1.0, 0.002);
  // The zoomed view shows new content at its borders; rotation stays within 0.1 degrees.
  EXPECT_NEAR(deg(r.rotation), 0.0, 0.1);
  EXPECT_LT(r.shift, 0.3);
  const double expected_bin = kN / 2 - std::log(zoom) / registrar.logZoomPerBin();
  EXPECT_NEAR(test::argmax(r.zoom_energy), expected_bin, 1.0);
  expectFiniteSigmas(r);
}

INSTANTIATE_TEST_SUITE_P(Zooms, PureZoom, ::testing::Values(0.8, 0.87, 0.95, 1.02, 1.1, 1.18, 1.25));

TEST(Registration, SwappedInputsInvertTheMotion) {
  sim::ViewMotion motion;
  motion.rotation = rad(8.0);
  motion.zoom = 1.07;
  const auto pair = test::warpedPair(motion);
  const PairRegistration forward = test::registerImages(pair.older, pair.newer);
  const PairRegistration backward = test::registerImages(pair.newer, pair.older);
  EXPECT_NEAR(deg(backward.rotation), -deg(forward.rotation), 0.05);
  EXPECT_NEAR(backward.zoom * forward.zoom, 1.0, 0.002);
  EXPECT_NEAR(deg(forward.rotation), 8.0, 0.05);
  EXPECT_NEAR(forward.zoom, 1.07, 0.002);
}

TEST(Registration, CombinedWarpGivesShiftInNewerAxes) {
  sim::ViewMotion motion;
  motion.rotation = rad(-12.0);
  motion.zoom = 1.08;
  motion.shift = {7.5, -4.25};
  const auto pair = test::warpedPair(motion);
  const PairRegistration r = test::registerImages(pair.older, pair.newer);
  ASSERT_EQ(r.status, RegistrationStatus::kOk);
  EXPECT_NEAR(deg(r.rotation), -12.0, 0.05);
  EXPECT_NEAR(r.zoom, 1.08, 0.002);
  EXPECT_NEAR(r.translation.x, 7.5, 0.2);
  EXPECT_NEAR(r.translation.y, -4.25, 0.2);
}

// A reader thread's builder correlates each frame with the ones before it
// (SpectraBuilder::correlateWithRecent); the Registrar takes those surfaces instead of computing them,
// and must register exactly as it would have.
TEST(Registration, RotationZoomCorrelatedAheadRegistersExactlyAsComputedHere) {
  sim::ViewMotion first, second;
  first.rotation = rad(6.0);
  first.zoom = 1.05;
  first.shift = {9.0, -3.5};
  second.rotation = rad(-11.0);
  second.zoom = 0.96;
  second.shift = {-14.0, 6.0};
  const auto a = test::warpedPair(first), b = test::warpedPair(second);
  const cv::Mat unrelated = test::warpedPair(second, kN, 11).newer;  // another texture
  const cv::Mat images[4] = {a.older, a.newer, b.newer, unrelated};
  const auto context = test::sharedContext(kN);
  SpectraBuilder ahead(context), plain(context);
  ahead.setLookback(2);
  std::vector<FrameSpectra> with, without;
  for (const cv::Mat& image : images) {
    with.push_back(ahead.build(image));
    ahead.correlateWithRecent(with.back());
    without.push_back(plain.build(image));
  }
  ASSERT_EQ(with[2].correlated.size(), 2u);
  EXPECT_EQ(with[2].correlated[0].older_serial, with[0].serial);
  EXPECT_EQ(with[2].correlated[1].older_serial, with[1].serial);
  EXPECT_TRUE(without[2].correlated.empty());
  Registrar registrar(context);
  const auto same = [](const PairRegistration& x, const PairRegistration& y) {
    return x.status == y.status && x.rotation == y.rotation && x.zoom == y.zoom &&
           x.translation == y.translation && x.peak_confidence == y.peak_confidence &&
           x.rotation_zoom_candidate == y.rotation_zoom_candidate && x.zoom_energy == y.zoom_energy &&
           x.translation_energy == y.translation_energy;
  };
  // Twice each: a pair whose first rotation/zoom candidate does not register (the unrelated
  // frame) tries the next ones, clearing the surface around those tried, which must not reach
  // the frame's own copy.
  for (const auto& [older, newer] : {std::pair{0, 2}, std::pair{1, 2}, std::pair{0, 1}, std::pair{2, 3}}) {
    const PairRegistration computed = registrar.registerPair(without[older], without[newer]);
    for (int run = 0; run < 2; ++run) {
      const PairRegistration taken = registrar.registerPair(with[older], with[newer]);
      EXPECT_TRUE(same(taken, computed)) << older << "-" << newer << " run " << run;
    }
    EXPECT_EQ(computed.status == RegistrationStatus::kOk, newer != 3) << older << "-" << newer;
  }
  // A frame the builder did not see (another builder's) is correlated here.
  const PairRegistration foreign = registrar.registerPair(without[0], with[2]);
  EXPECT_TRUE(same(foreign, registrar.registerPair(without[0], without[2])));
  EXPECT_NEAR(deg(foreign.rotation), -11.0, 0.05);
  // A surface of another size (a caller's own FrameSpectra) is not taken.
  FrameSpectra tampered = with[2];
  tampered.correlated[1].power = cv::Mat2f(8, 8, cv::Vec2f(1.0f, 0.0f));
  EXPECT_TRUE(same(registrar.registerPair(with[1], tampered), registrar.registerPair(without[1], without[2])));
}

TEST(Registration, ClassicMethodFindsTheSingleDominantMotion) {
  sim::ViewMotion motion;
  motion.rotation = rad(20.0);
  motion.zoom = 0.9;
  motion.shift = {-11.0, 6.5};
  const auto pair = test::warpedPair(motion);
  const PairRegistration r =
      test::registerImages(pair.older, pair.newer, RegistrationMethod::kClassic);
  ASSERT_EQ(r.status, RegistrationStatus::kOk);
  EXPECT_NEAR(deg(r.rotation), 20.0, 0.1);
  EXPECT_NEAR(r.zoom, 0.9, 0.002);
  EXPECT_NEAR(r.translation.x, -11.0, 0.2);
  EXPECT_NEAR(r.translation.y, 6.5, 0.2);
  EXPECT_TRUE(r.zoom_energy.empty());
  EXPECT_TRUE(r.translation_energy.empty());
  expectFiniteSigmas(r);
}

// Local maxima of v within +-tolerance of `bin` whose height is at least `fraction` of the
// vector's maximum (energies are cubed correlations: a plane of a third of the peak's height
// keeps a few percent).
bool hasPeakNear(const std::vector<float>& v, double bin, double tolerance, double fraction) {
  const float top = v[test::argmax(v)];
  for (int j = 1; j + 1 < static_cast<int>(v.size()); ++j) {
    if (std::fabs(j - bin) > tolerance) continue;
    if (v[j] >= v[j - 1] && v[j] >= v[j + 1] && v[j] >= fraction * top) return true;
  }
  return false;
}

TEST(Registration, TwoPlanesGiveTwoTranslationEnergyPeaks) {
  const cv::Mat1f ground = sim::proceduralTexture({2048, 2048}, 11, sim::TextureStyle::kCells, 40);
  const cv::Mat1f roofs = sim::proceduralTexture({2048, 2048}, 12, sim::TextureStyle::kCells, 40);
  const cv::Mat1f mask = sim::blockMask({2048, 2048}, 13, 96.0, 0.7);
  const cv::Point2d centre(1024, 1024);
  const double direction = rad(35.0);
  const cv::Point2d unit(std::cos(direction), std::sin(direction));
  const cv::Mat1f older = sim::renderTwoLayerView(ground, roofs, mask, centre, {0, 0}, {0, 0}, kN);
  const cv::Mat1f newer =
      sim::renderTwoLayerView(ground, roofs, mask, centre, unit * 10.0, unit * 20.0, kN);
  const PairRegistration r = test::registerImages(older, newer);
  ASSERT_NE(r.status, RegistrationStatus::kTextureless);
  EXPECT_NEAR(std::remainder(r.direction - direction, 2 * CV_PI), 0.0, 0.03);
  EXPECT_TRUE(hasPeakNear(r.translation_energy, 10.0 / 0.75, 1.0, 0.03));
  EXPECT_TRUE(hasPeakNear(r.translation_energy, 20.0 / 0.75, 1.0, 0.03));

  // The next pair at 1.5 times the speed stretches the vector by 1.5.
  const cv::Mat1f faster =
      sim::renderTwoLayerView(ground, roofs, mask, centre, unit * 25.0, unit * 50.0, kN);
  const PairRegistration r2 = test::registerImages(newer, faster);
  EXPECT_TRUE(hasPeakNear(r2.translation_energy, 15.0 / 0.75, 1.0, 0.03));
  EXPECT_TRUE(hasPeakNear(r2.translation_energy, 30.0 / 0.75, 1.0, 0.03));
}

// The estimator reads the layers along the predicted direction where the chosen peak lies off it
// (an alias): the energy vector along a given direction has the layers' peaks there, and none
// along the opposite or a perpendicular direction.
TEST(Registration, TheEnergyVectorAlongAGivenDirectionHoldsTheLayersMovingAlongIt) {
  const cv::Mat1f ground = sim::proceduralTexture({2048, 2048}, 11, sim::TextureStyle::kCells, 40);
  const cv::Mat1f roofs = sim::proceduralTexture({2048, 2048}, 12, sim::TextureStyle::kCells, 40);
  const cv::Mat1f mask = sim::blockMask({2048, 2048}, 13, 96.0, 0.7);
  const cv::Point2d centre(1024, 1024);
  const double direction = rad(-62.0);
  const cv::Point2d unit(std::cos(direction), std::sin(direction));
  const cv::Mat1f older = sim::renderTwoLayerView(ground, roofs, mask, centre, {0, 0}, {0, 0}, kN);
  const cv::Mat1f newer =
      sim::renderTwoLayerView(ground, roofs, mask, centre, unit * 30.0, unit * 45.0, kN);
  Registrar registrar(test::sharedContext(kN));
  const FrameSpectra a = registrar.analyse(older), b = registrar.analyse(newer);
  EXPECT_TRUE(registrar.translationEnergyAlong(a, b, direction, 30.0).empty());  // not registered yet
  const PairRegistration r = registrar.registerPair(a, b);
  ASSERT_EQ(r.status, RegistrationStatus::kOk);
  EXPECT_TRUE(registrar.translationEnergyAlong(b, a, direction, 30.0).empty());  // another pair
  const double bin = registrar.shiftPerBin();
  const std::vector<float> along = registrar.translationEnergyAlong(a, b, direction, 30.0);
  ASSERT_FALSE(along.empty());
  EXPECT_TRUE(hasPeakNear(along, 30.0 / bin, 1.0, 0.03));
  EXPECT_TRUE(hasPeakNear(along, 45.0 / bin, 1.0, 0.03));
  for (const double off : {CV_PI, CV_PI / 2.0}) {
    const std::vector<float> elsewhere = registrar.translationEnergyAlong(a, b, direction + off, 30.0);
    ASSERT_EQ(elsewhere.size(), along.size());
    // Normalised to unit sum: a vector without a layer spreads its energy thin.
    for (const double shift : {30.0, 45.0}) {
      const std::size_t j = static_cast<std::size_t>(std::lround(shift / bin));
      EXPECT_LT(elsewhere[j], 0.25 * along[j]) << off << " " << shift;
    }
    EXPECT_LT(elsewhere[test::argmax(elsewhere)], along[static_cast<std::size_t>(std::lround(45.0 / bin))]) << off;
  }
}

TEST(Registration, ConstantAndBlackFramesAreTextureless) {
  const auto pair = test::warpedPair(sim::ViewMotion{});
  const cv::Mat1f black(kN, kN, 0.0f);
  const cv::Mat1f grey(kN, kN, 0.5f);
  for (const cv::Mat1f& flat : {black, grey}) {
    const PairRegistration r = test::registerImages(pair.older, flat);
    EXPECT_EQ(r.status, RegistrationStatus::kTextureless);
    EXPECT_EQ(r.confidence, 0.0);
    EXPECT_TRUE(std::isfinite(r.rotation) && std::isfinite(r.zoom) && std::isfinite(r.shift));
    EXPECT_FALSE(r.usable());
  }
}

TEST(Registration, NanImageGivesAFiniteUnusableResult) {
  const auto pair = test::warpedPair(sim::ViewMotion{});
  const cv::Mat1f nan_image(kN, kN, std::numeric_limits<float>::quiet_NaN());
  const PairRegistration r = test::registerImages(pair.older, nan_image);
  EXPECT_EQ(r.status, RegistrationStatus::kTextureless);
  EXPECT_TRUE(std::isfinite(r.translation.x) && std::isfinite(r.rotation));
}

TEST(Registration, SomeNanPixelsAreReplacedAndCounted) {
  sim::ViewMotion motion;
  motion.shift = {6.0, 3.0};
  auto pair = test::warpedPair(motion);
  cv::Mat1f damaged = pair.newer.clone();
  damaged(cv::Rect(100, 100, 20, 20)).setTo(std::numeric_limits<float>::quiet_NaN());
  damaged(300, 300) = std::numeric_limits<float>::infinity();
  Registrar registrar(test::sharedContext(kN));
  const FrameSpectra a = registrar.analyse(pair.older);
  const FrameSpectra b = registrar.analyse(damaged);
  EXPECT_EQ(b.invalid_pixels, 401);
  const PairRegistration r = registrar.registerPair(a, b);
  ASSERT_EQ(r.status, RegistrationStatus::kOk);
  EXPECT_NEAR(r.translation.x, 6.0, 0.2);
  EXPECT_NEAR(r.translation.y, 3.0, 0.2);
}

TEST(Registration, NoiseWeightingKeepsADullNoisyPairConfident) {
  // A dull texture (grey std 6 of 255) under sensor noise of 8 grey levels, moved by a known
  // shift: with the noise-dominated frequencies weighted down the translation peak stands out;
  // the plain phase correlation leaves it at the edge of being refused.
  const auto pair = test::warpedPair(sim::ViewMotion{0.0, 1.0, {23.5, -41.25}});
  const auto dull = [](const cv::Mat1f& image, int seed) {
    cv::Scalar mean, stddev;
    cv::meanStdDev(image, mean, stddev);
    cv::Mat1f out = (image - mean[0]) * ((6.0 / 255.0) / stddev[0]) + 0.5;
    cv::Mat1f noise(image.size());
    cv::RNG(seed).fill(noise, cv::RNG::NORMAL, 0.0, 8.0 / 255.0);
    return cv::Mat1f(out + noise);
  };
  const cv::Mat1f older = dull(pair.older, 1), newer = dull(pair.newer, 2);
  const PairRegistration weighted = test::registerImages(older, newer);
  RegistrationConfig plain_config;
  plain_config.noise_weighting = false;
  plain_config.fft_planning = FftPlanning::kEstimate;
  Registrar plain(plain_config);
  const PairRegistration unweighted = plain.registerPair(plain.analyse(older), plain.analyse(newer));
  EXPECT_EQ(weighted.status, RegistrationStatus::kOk);
  EXPECT_GT(weighted.confidence, 0.6);
  EXPECT_NEAR(weighted.translation.x, 23.5, 0.3);
  EXPECT_NEAR(weighted.translation.y, -41.25, 0.3);
  EXPECT_LT(unweighted.confidence, weighted.confidence - 0.4);
}

TEST(Registration, UnrelatedImagesHaveLowConfidence) {
  const auto a = test::warpedPair(sim::ViewMotion{}, kN, 21);
  const auto b = test::warpedPair(sim::ViewMotion{}, kN, 22);
  const PairRegistration r = test::registerImages(a.older, b.older);
  EXPECT_EQ(r.status, RegistrationStatus::kLowConfidence);
  EXPECT_LT(r.confidence, 0.15);
}

TEST(Registration, BadInputIsAClearError) {
  Registrar registrar(test::sharedContext(kN));
  EXPECT_THROW(registrar.analyse(cv::Mat()), InputError);
  EXPECT_THROW(registrar.registerPair(FrameSpectra{}, FrameSpectra{}), InputError);
  // Frames analysed at another size cannot be paired.
  Registrar small(test::sharedContext(128));
  const auto pair = test::warpedPair(sim::ViewMotion{});
  const FrameSpectra big_frame = registrar.analyse(pair.older);
  const FrameSpectra small_frame = small.analyse(pair.older);
  EXPECT_THROW(registrar.registerPair(big_frame, small_frame), InputError);
  try {
    registrar.analyse(cv::Mat(64, 64, CV_8SC1, cv::Scalar(1)));
    FAIL() << "a signed 8-bit image was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("CV_8S"), std::string::npos) << e.what();
  }
}

TEST(Registration, TinyFramesAreRefusedWithTheirSize) {
  Registrar registrar(test::sharedContext(kN));
  for (const cv::Size size : {cv::Size(40, 30), cv::Size(63, 200), cv::Size(1, 1)}) {
    try {
      registrar.analyse(cv::Mat(size, CV_8UC1, cv::Scalar(7)));
      FAIL() << size << " was accepted";
    } catch (const InputError& e) {
      const std::string text = std::to_string(size.width) + "x" + std::to_string(size.height);
      EXPECT_NE(std::string(e.what()).find(text), std::string::npos) << e.what();
    }
  }
  EXPECT_NO_THROW(registrar.analyse(cv::Mat(64, 100, CV_8UC1, cv::Scalar(7))));
}

// Frames smaller than the working size are upscaled, which registers worse: the warning the
// node and oefmt_offline give names the size to set; none for frames at least that large.
TEST(Registration, UpscaledFramesGetAWarningNamingTheSize) {
  const std::string warning = upscalingWarning(cv::Size(321, 256), 512);
  EXPECT_NE(warning.find("(321x256)"), std::string::npos) << warning;
  EXPECT_NE(warning.find("upscaled to registration.size 512"), std::string::npos) << warning;
  EXPECT_NE(warning.find("at most 256"), std::string::npos) << warning;
  EXPECT_NE(upscalingWarning(cv::Size(640, 255), 512).find("at most 254"), std::string::npos);
  EXPECT_TRUE(upscalingWarning(cv::Size(640, 512), 512).empty());
  EXPECT_TRUE(upscalingWarning(cv::Size(4056, 3040), 512).empty());
}

// A full-resolution 4056 x 3040 colour frame (the authors' camera) registers like its
// resized centre square: the crop happens before any conversion.
TEST(Registration, FullResolutionCameraFramesRegister) {
  const int n = 128;
  cv::Mat1f crop;
  cv::normalize(test::sceneTexture(11)(cv::Rect(0, 0, 400, 300)), crop, 0.0, 255.0, cv::NORM_MINMAX);
  cv::Mat big_grey, big8;
  cv::resize(crop, big_grey, cv::Size(4056, 3040), 0, 0, cv::INTER_CUBIC);
  big_grey.convertTo(big8, CV_8U);
  cv::Mat older, newer;
  cv::cvtColor(big8, older, cv::COLOR_GRAY2BGR);
  // The newer frame: the scene moved 47 px right (about 2 px at 128 / 3040 scale).
  const cv::Mat shift = (cv::Mat_<double>(2, 3) << 1, 0, 47, 0, 1, 0);
  cv::warpAffine(older, newer, shift, older.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT);
  Registrar registrar(test::sharedContext(n));
  const FrameSpectra a = registrar.analyse(older);
  const FrameSpectra b = registrar.analyse(newer);
  const PairRegistration r = registrar.registerPair(a, b);
  EXPECT_EQ(r.status, RegistrationStatus::kOk);
  EXPECT_NEAR(r.translation.x, 47.0 * n / 3040.0, 0.2);
  EXPECT_NEAR(r.translation.y, 0.0, 0.2);
  EXPECT_NEAR(r.zoom, 1.0, 0.002);
}

TEST(Registration, SmallSizesWork) {
  sim::ViewMotion motion;
  motion.shift = {3.5, -2.0};
  motion.rotation = rad(5.0);
  const auto pair = test::warpedPair(motion, 128);
  const PairRegistration r = test::registerImages(pair.older, pair.newer);
  EXPECT_EQ(r.status, RegistrationStatus::kOk);
  EXPECT_NEAR(deg(r.rotation), 5.0, 0.3);
  EXPECT_NEAR(r.translation.x, 3.5, 0.3);
  EXPECT_NEAR(r.translation.y, -2.0, 0.3);
}

}  // namespace
}  // namespace oefmt
