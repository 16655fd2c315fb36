// SPDX-License-Identifier: GPL-3.0-or-later
#include "support/fixtures.h"

#include <algorithm>
#include <map>
#include <mutex>

#include "oefmt/sim/texture.h"

namespace oefmt {
namespace test {

std::shared_ptr<const SpectralContext> sharedContext(int n) {
  static std::mutex mutex;
  static std::map<int, std::shared_ptr<const SpectralContext>> contexts;
  std::lock_guard<std::mutex> lock(mutex);
  auto& context = contexts[n];
  if (!context) {
    RegistrationConfig config;
    config.size = n;
    context = std::make_shared<const SpectralContext>(config);
  }
  return context;
}

const cv::Mat1f& sceneTexture(unsigned seed) {
  static std::mutex mutex;
  static std::map<unsigned, cv::Mat1f> textures;
  std::lock_guard<std::mutex> lock(mutex);
  cv::Mat1f& texture = textures[seed];
  if (texture.empty()) texture = sim::proceduralTexture(cv::Size(2048, 2048), seed);
  return texture;
}

ImagePair warpedPair(const sim::ViewMotion& motion, int n, unsigned seed) {
  const cv::Mat1f& texture = sceneTexture(seed);
  const cv::Point2d centre(texture.cols / 2.0, texture.rows / 2.0);
  return {sim::renderView(texture, centre, sim::ViewMotion{}, n),
          sim::renderView(texture, centre, motion, n)};
}

PairRegistration registerImages(const cv::Mat& older, const cv::Mat& newer,
                                RegistrationMethod method) {
  const int n = std::max(64, std::min(older.rows, older.cols) / 2 * 2);
  Registrar registrar(sharedContext(n));
  const FrameSpectra a = registrar.analyse(older);
  const FrameSpectra b = registrar.analyse(newer);
  return registrar.registerPair(a, b, method);
}

int argmax(const std::vector<float>& v) {
  return static_cast<int>(std::max_element(v.begin(), v.end()) - v.begin());
}

std::vector<double> levelHeights(const sim::FlightOptions& options, const std::vector<double>& fractions) {
  const double altitude = sim::planFlight(options).track.altitude;
  std::vector<double> heights;
  for (double fraction : fractions) heights.push_back(fraction * altitude);
  return heights;
}

}  // namespace test
}  // namespace oefmt
