// SPDX-License-Identifier: GPL-3.0-or-later
// Shared test helpers: one registration context per size, textures and warped pairs.
#pragma once

#include <memory>
#include <vector>

#include <opencv2/core.hpp>

#include "oefmt/registration/registration.h"
#include "oefmt/sim/flight.h"
#include "oefmt/sim/similarity_views.h"

namespace oefmt {
namespace test {

/// The default configuration at size n, planned once per test binary and shared.
std::shared_ptr<const SpectralContext> sharedContext(int n = 512);

/// A 2048 x 2048 textured scene (seeded).
const cv::Mat1f& sceneTexture(unsigned seed = 7);

/// Reference view and a view moved by `motion`, both n x n, from sceneTexture(seed).
struct ImagePair {
  cv::Mat1f older;
  cv::Mat1f newer;
};
ImagePair warpedPair(const sim::ViewMotion& motion, int n = 512, unsigned seed = 7);

/// Registers two images with a fresh Registrar on the shared context.
PairRegistration registerImages(const cv::Mat& older, const cv::Mat& newer,
                                RegistrationMethod method = RegistrationMethod::kEnergyVectors);

/// Index of the largest element.
int argmax(const std::vector<float>& v);

inline double deg(double radians) { return radians * 180.0 / CV_PI; }
inline double rad(double degrees) { return degrees * CV_PI / 180.0; }

/// Raised levels at the given fractions of the flight's altitude (as oefmt_simulate's default
/// levels are), for a scene other than the default's.
std::vector<double> levelHeights(const sim::FlightOptions& options, const std::vector<double>& fractions);

}  // namespace test
}  // namespace oefmt
