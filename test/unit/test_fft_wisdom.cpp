// SPDX-License-Identifier: GPL-3.0-or-later
// FFTW wisdom kept between runs: where it lives, that it round-trips, and that a damaged file
// costs only the speed-up, never a wrong transform.
#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <optional>
#include <string>

#include "support/temp_dir.h"
#include "oefmt/io/fft_wisdom.h"
#include "oefmt/registration/fft.h"

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

// Tests that make FFTW forget its wisdom read the file back after, so that the tests after them
// do not measure their plans again (seconds each at N = 512 with the default patient planning).
class FftWisdom : public ::testing::Test {
 protected:
  void TearDown() override { importFftWisdom(fftWisdomFile()); }
};

// forward then inverse gives the input times N^2 when the plans are sound.
void expectRoundTrip(int n, FftPlanning planning = FftPlanning::kMeasure) {
  const Fft2d fft(n, planning);
  cv::Mat1f image(n, n), back;
  cv::randu(image, -1.0f, 1.0f);
  cv::Mat2f spectrum;
  fft.forward(image, spectrum);
  fft.inverse(spectrum, back);
  EXPECT_LT(cv::norm(back / static_cast<float>(n * n), image, cv::NORM_INF), 1e-5);
}

TEST_F(FftWisdom, ExportedWisdomImportsAgain) {
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

TEST_F(FftWisdom, DamagedOrMissingFileIsRefusedAndPlanningStillWorks) {
  test::TempDir dir;
  const std::string file = dir / "wisdom";
  std::ofstream(file) << "(fftw-3.3.10 fftwf_wisdom #x0 #x1\n  (\"garbage\" 1 2 3 ((((\n";
  EXPECT_FALSE(importFftWisdom(file));
  expectRoundTrip(40);
  EXPECT_FALSE(importFftWisdom(dir / "missing"));
  EXPECT_FALSE(importFftWisdom(dir.path().string()));  // a folder
  EXPECT_FALSE(exportFftWisdom(""));
}

// Forgets every plan FFTW knows: a damaged wisdom file is refused as a whole.
void forgetAllWisdom() {
  test::TempDir dir;
  const std::string file = dir / "damaged";
  std::ofstream(file) << "(fftw-3.3.10 fftwf_wisdom #x0 #x1\n  (\"garbage\" ((((\n";
  ASSERT_FALSE(importFftWisdom(file));
}

TEST_F(FftWisdom, KnowsWhenPlansStillNeedMeasuring) {
  constexpr int kN = 58;  // a size no other test plans
  fftPlansKnown(kN, FftPlanning::kMeasure);  // the wisdom file is read now, not after forgetting
  forgetAllWisdom();
  EXPECT_TRUE(fftPlansKnown(kN, FftPlanning::kEstimate)) << "estimating measures nothing";
  EXPECT_FALSE(fftPlansKnown(kN, FftPlanning::kMeasure));
  EXPECT_FALSE(fftPlansKnown(kN, FftPlanning::kPatient));
  expectRoundTrip(kN, FftPlanning::kMeasure);
  EXPECT_TRUE(fftPlansKnown(kN, FftPlanning::kMeasure));
  EXPECT_FALSE(fftPlansKnown(kN, FftPlanning::kPatient)) << "measured plans are not patient ones";
  expectRoundTrip(kN, FftPlanning::kPatient);
  EXPECT_TRUE(fftPlansKnown(kN, FftPlanning::kPatient));
  EXPECT_FALSE(fftPlansKnown(kN + 2, FftPlanning::kPatient)) << "wisdom is per size";
  EXPECT_FALSE(fftPlansKnown(57, FftPlanning::kMeasure)) << "odd sizes are refused";
}

// A newly set wisdom file is read before the next plan: a program chooses its file at start.
TEST_F(FftWisdom, ANewWisdomFileIsReadBeforeTheNextPlan) {
  constexpr int kN = 62;  // a size no other test plans
  test::TempDir dir;
  const std::string file = dir / "wisdom";
  expectRoundTrip(kN, FftPlanning::kMeasure);
  ASSERT_TRUE(exportFftWisdom(file));
  const std::string before = fftWisdomFile();
  forgetAllWisdom();
  EXPECT_FALSE(fftPlansKnown(kN, FftPlanning::kMeasure));
  setFftWisdomFile(file);
  EXPECT_EQ(fftWisdomFile(), file);
  EXPECT_TRUE(fftPlansKnown(kN, FftPlanning::kMeasure)) << "the new file was not read";
  setFftWisdomFile(before);
}

TEST_F(FftWisdom, DefaultPathFollowsTheEnvironment) {
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
