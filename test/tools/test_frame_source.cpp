// SPDX-License-Identifier: GPL-3.0-or-later
// oefmt_offline's PrefetchingSource: frames arrive in order, each with its own spectra; an error
// while reading or analysing a frame arrives after the frames before it, named; the reader stops
// there and when the consumer stops early.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <memory>
#include <string>
#include <thread>

#include "frame_source.h"
#include "oefmt/error.h"

namespace oefmt {
namespace {

// Frame k is a 1 x 1 image holding k; `failing_frame` makes next() throw there.
class CountingSource : public FrameSource {
 public:
  CountingSource(std::size_t frames, std::size_t failing_frame, std::atomic<std::size_t>* read)
      : frames_(frames), failing_frame_(failing_frame), read_(read) {}
  std::size_t size() const override { return frames_; }
  bool next(SourceFrame& frame) override {
    if (index_ >= frames_) return false;
    if (index_ == failing_frame_) throw InputError("frame " + std::to_string(index_) + " is corrupt");
    frame.index = index_;
    frame.stamp = 0.1 * static_cast<double>(index_);
    frame.name = "f" + std::to_string(index_);
    frame.image = cv::Mat1f(1, 1, static_cast<float>(index_));
    ++index_;
    if (read_ != nullptr) ++*read_;
    return true;
  }
  std::string describe() const override { return "counting"; }

 private:
  std::size_t frames_;
  std::size_t failing_frame_;
  std::atomic<std::size_t>* read_;
  std::size_t index_ = 0;
};

constexpr std::size_t kNever = static_cast<std::size_t>(-1);

// The analysis records the image's value as the texture; `failing_value` makes it throw.
PrefetchingSource::Analyse recordingAnalysis(float failing_value = -1.0f) {
  return [failing_value](SourceFrame& frame) {
    const float value = frame.image.at<float>(0, 0);
    if (value == failing_value) throw InputError("cannot analyse this image");
    frame.spectra = FrameSpectra();
    frame.spectra.texture = value;
  };
}

TEST(PrefetchingSource, DeliversEveryFrameInOrderWithItsOwnSpectra) {
  PrefetchingSource source(std::make_unique<CountingSource>(50, kNever, nullptr), 2, recordingAnalysis());
  SourceFrame frame;
  std::size_t count = 0;
  while (source.next(frame)) {
    EXPECT_EQ(frame.index, count);
    EXPECT_DOUBLE_EQ(frame.spectra.texture, static_cast<double>(count));
    EXPECT_TRUE(frame.image.empty());  // released once analysed
    EXPECT_EQ(frame.image_size, cv::Size(1, 1));
    ++count;
  }
  EXPECT_EQ(count, 50u);
  EXPECT_FALSE(source.next(frame));  // and stays at the end
}

// The spare work (marked as the frame's mean) runs only where the consumer still has a frame
// queued when the frame is analysed: never while it waits for each frame in turn, and on every
// frame but the first when the reader runs ahead of a consumer that has not started yet.
PrefetchingSource::Analyse markingSpareWork() {
  return [](SourceFrame& frame) { frame.spectra.mean = 1.0f; };
}

TEST(PrefetchingSource, SpareWorkRunsOnlyWhileTheConsumerHasAFrameQueued) {
  const PrefetchingSource::Analyse record = recordingAnalysis();
  {
    // The consumer starts only once all five frames are analysed.
    std::atomic<std::size_t> analysed{0};
    const auto counted = [record, &analysed](SourceFrame& frame) {
      record(frame);
      ++analysed;
    };
    PrefetchingSource source(std::make_unique<CountingSource>(5, kNever, nullptr), 8, counted, markingSpareWork());
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
    while (analysed.load() < 5 && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    SourceFrame frame;
    for (std::size_t k = 0; k < 5; ++k) {
      ASSERT_TRUE(source.next(frame));
      EXPECT_EQ(frame.spectra.mean, k == 0 ? 0.0f : 1.0f) << k;
    }
  }
  {
    // Frame k is analysed only once the consumer has taken every frame before it.
    std::atomic<std::size_t> taken{0};
    const auto paced = [record, &taken](SourceFrame& frame) {
      // Bounded, so that a failing test cannot hang in the source's destructor.
      const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(10);
      while (taken.load() < frame.index && std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
      record(frame);
    };
    PrefetchingSource source(std::make_unique<CountingSource>(4, kNever, nullptr), 8, paced, markingSpareWork());
    SourceFrame frame;
    for (std::size_t k = 0; k < 4; ++k) {
      ASSERT_TRUE(source.next(frame));
      ++taken;
      EXPECT_EQ(frame.spectra.mean, 0.0f) << k;
    }
  }
}

TEST(PrefetchingSource, WithoutAnalysisDeliversTheImages) {
  PrefetchingSource source(std::make_unique<CountingSource>(5, kNever, nullptr), 3);
  SourceFrame frame;
  for (std::size_t k = 0; k < 5; ++k) {
    ASSERT_TRUE(source.next(frame));
    ASSERT_FALSE(frame.image.empty());
    EXPECT_FLOAT_EQ(frame.image.at<float>(0, 0), static_cast<float>(k));
    EXPECT_TRUE(frame.spectra.empty());
  }
  EXPECT_FALSE(source.next(frame));
}

// Frames 0 .. good_frames - 1 arrive in order, then next() throws `message`.
void expectFramesThenError(PrefetchingSource& source, std::size_t good_frames, const char* message) {
  SourceFrame frame;
  for (std::size_t k = 0; k < good_frames; ++k) {
    ASSERT_TRUE(source.next(frame));
    EXPECT_EQ(frame.index, k);
  }
  try {
    source.next(frame);
    ADD_FAILURE() << "no error after " << good_frames << " frames";
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), message);
  }
}

TEST(PrefetchingSource, DecodingErrorArrivesAfterTheFramesBeforeIt) {
  PrefetchingSource source(std::make_unique<CountingSource>(20, 7, nullptr), 2, recordingAnalysis());
  expectFramesThenError(source, 7, "frame 7 is corrupt");
}

TEST(PrefetchingSource, AnalysisErrorNamesTheFrameAndStopsThere) {
  std::atomic<std::size_t> read{0};
  PrefetchingSource source(std::make_unique<CountingSource>(20, kNever, &read), 2, recordingAnalysis(5.0f));
  expectFramesThenError(source, 5, "f5: cannot analyse this image");
  EXPECT_LT(read.load(), 20u);  // the reader stopped there, not reading the whole source
}

TEST(PrefetchingSource, StoppingEarlyDoesNotWaitForTheRest) {
  std::atomic<std::size_t> read{0};
  {
    PrefetchingSource source(std::make_unique<CountingSource>(1000000, kNever, &read), 2, recordingAnalysis());
    SourceFrame frame;
    ASSERT_TRUE(source.next(frame));
    ASSERT_TRUE(source.next(frame));
  }  // destroyed with both threads mid-stream: returns (a hang would time the test out)
  EXPECT_LT(read.load(), 100u);  // bounded read-ahead: a few frames, not the source
}

}  // namespace
}  // namespace oefmt
