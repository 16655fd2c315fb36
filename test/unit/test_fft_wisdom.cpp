// SPDX-License-Identifier: GPL-3.0-or-later
// FFTW wisdom kept between runs: where it lives, that it round-trips, and that a damaged file
// costs only the speed-up, never a wrong transform.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <optional>
#include <string>

#include "io/temp_dir.h"
#include "oefmt/fft.h"

namespace oefmt {
namespace {

// Sets an environment variable for one test and restores it after.
class ScopedEnvironment {
 public:
  ScopedEnvironment(const char* name, const char* value) : name_(name) {
    if (const char* old = std::getenv(name)) old_ = std::string(old);
    if (value != nullptr) {
      setenv(name, value, 1);
    } else {
      unsetenv(name);
    }
  }
  ~ScopedEnvironment() {
    if (old_) {
      setenv(name_.c_str(), old_->c_str(), 1);
    } else {
      unsetenv(name_.c_str());
    }
  }

 private:
  std::string name_;
  std::optional<std::string> old_;
};

// forward then inverse gives the input times N^2 when the plans are sound.
void expectRoundTrip(int n) {
  const Fft2d fft(n, FftPlanning::kMeasure);
  cv::Mat1f image(n, n), back;
  cv::randu(image, -1.0f, 1.0f);
  cv::Mat2f spectrum;
  fft.forward(image, spectrum);
  fft.inverse(spectrum, back);
  EXPECT_LT(cv::norm(back / static_cast<float>(n * n), image, cv::NORM_INF), 1e-5);
}

TEST(FftWisdom, ExportedWisdomImportsAgain) {
  test::TempDir dir;
  const std::string file = dir / "cache/wisdom";
  expectRoundTrip(48);
  ASSERT_TRUE(exportFftWisdom(file)) << "the cache folder is created as needed";
  std::ifstream in(file);
  std::string first;
  std::getline(in, first);
  EXPECT_EQ(first.rfind("(fftw-3", 0), 0u) << first;
  EXPECT_TRUE(importFftWisdom(file));
  expectRoundTrip(48);
}

TEST(FftWisdom, DamagedOrMissingFileIsRefusedAndPlanningStillWorks) {
  test::TempDir dir;
  const std::string file = dir / "wisdom";
  std::ofstream(file) << "(fftw-3.3.10 fftwf_wisdom #x0 #x1\n  (\"garbage\" 1 2 3 ((((\n";
  EXPECT_FALSE(importFftWisdom(file));
  expectRoundTrip(40);
  EXPECT_FALSE(importFftWisdom(dir / "missing"));
  EXPECT_FALSE(importFftWisdom(dir.path().string()));  // a folder
  EXPECT_FALSE(exportFftWisdom(""));
}

TEST(FftWisdom, DefaultPathFollowsTheEnvironment) {
  {
    ScopedEnvironment custom("OEFMT_FFTW_WISDOM", "/some/where/wisdom");
    EXPECT_EQ(defaultFftWisdomPath(), "/some/where/wisdom");
  }
  {
    ScopedEnvironment off("OEFMT_FFTW_WISDOM", "none");
    EXPECT_EQ(defaultFftWisdomPath(), "");
  }
  ScopedEnvironment unset("OEFMT_FFTW_WISDOM", nullptr);
  {
    ScopedEnvironment xdg("XDG_CACHE_HOME", "/var/cache/me");
    EXPECT_EQ(defaultFftWisdomPath().rfind("/var/cache/me/oefmt/fftwf-wisdom-", 0), 0u);
  }
  ScopedEnvironment no_xdg("XDG_CACHE_HOME", nullptr);
  {
    ScopedEnvironment home("HOME", "/home/pilot");
    EXPECT_EQ(defaultFftWisdomPath().rfind("/home/pilot/.cache/oefmt/fftwf-wisdom-", 0), 0u);
  }
  ScopedEnvironment no_home("HOME", nullptr);
  EXPECT_EQ(defaultFftWisdomPath(), "") << "nowhere to keep it: no file";
}

}  // namespace
}  // namespace oefmt
