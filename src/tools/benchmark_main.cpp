// SPDX-License-Identifier: GPL-3.0-or-later
// oefmt_benchmark: time of one pair registration at N = 512 and of each of its stages.
// Single-threaded by default (OpenCV's thread pool off; FFTW is single-threaded);
// pass --threads K to let OpenCV use K threads.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "command_line.h"
#include "oefmt/registration/energy_vector.h"
#include "oefmt/io/image_decoding.h"
#include "oefmt/io/image_encoding.h"
#include "oefmt/registration/phase_correlation.h"
#include "oefmt/registration/registration.h"
#include "oefmt/registration/warp.h"
#include "oefmt/sim/similarity_views.h"
#include "oefmt/sim/texture.h"
#include "oefmt/io/fft_wisdom.h"

namespace {

constexpr int kN = 512;

// Inputs shared by every benchmark: two 8-bit BGR camera frames related by a known motion (a
// rotation and zoom: the warp runs), and a frame shifted only (level flight at a steady
// heading: registration.identity_warp_px skips the warp).
struct Inputs {
  std::shared_ptr<const oefmt::SpectralContext> context;
  cv::Mat older_raw, newer_raw;
  oefmt::PreparedImage older, newer, shifted;
  oefmt::FrameSpectra older_spectra, newer_spectra;  // of older and newer
  std::vector<std::uint8_t> older_png;  // older_raw as a PNG file's bytes

  Inputs() {
    oefmt::RegistrationConfig config;
    config.size = kN;
    context = std::make_shared<const oefmt::SpectralContext>(config);
    const cv::Mat1f texture = oefmt::sim::proceduralTexture({2048, 2048}, 3);
    oefmt::sim::ViewMotion motion;
    motion.rotation = 0.05;
    motion.zoom = 1.03;
    motion.shift = {14.0, -9.0};
    older_raw = toBgr(oefmt::sim::renderView(texture, {1024, 1024}, {}, kN));
    newer_raw = toBgr(oefmt::sim::renderView(texture, {1024, 1024}, motion, kN));
    older = oefmt::prepareImage(older_raw, kN);
    older_png = oefmt::encodeImage("png", older_raw);
    newer = oefmt::prepareImage(newer_raw, kN);
    oefmt::sim::ViewMotion shift_only;
    shift_only.shift = {14.0, -9.0};
    shifted = oefmt::prepareImage(toBgr(oefmt::sim::renderView(texture, {1024, 1024}, shift_only, kN)), kN);
    oefmt::SpectraBuilder builder(context);
    older_spectra = builder.build(older);
    newer_spectra = builder.build(newer);
  }

  static cv::Mat toBgr(const cv::Mat1f& grey) {
    cv::Mat grey8, bgr;
    grey.convertTo(grey8, CV_8U, 255.0);
    cv::cvtColor(grey8, bgr, cv::COLOR_GRAY2BGR);
    return bgr;
  }
};

Inputs& inputs() {
  static Inputs instance;
  return instance;
}

// One 512 x 512 FFTW forward + inverse pair (real <-> half spectrum) as the pipeline runs them;
// the forward transform regenerates what the in-place inverse overwrites.
void fftPair(cv::Mat2f& buffer) {
  const oefmt::Fft2d& fft = inputs().context->fft();
  fft.forward(inputs().newer.grey, buffer);
  fft.inverseInPlace(buffer);
}

// Seconds of one fftPair right now (the fastest of three batches of ten): the yardstick of the
// "fft_pairs" counters below.
double fftPairSeconds() {
  cv::Mat2f buffer;
  inputs().context->fft().inPlaceInput(buffer);
  double best = 1e9;
  for (int batch = 0; batch < 3; ++batch) {
    const auto start = std::chrono::steady_clock::now();
    for (int i = 0; i < 10; ++i) fftPair(buffer);
    const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
    best = std::min(best, elapsed.count() / 10);
  }
  return best;
}

// Jiffies of all CPUs since boot: {stolen by the hypervisor, all}; {0, 0} without /proc/stat.
std::pair<double, double> cpuTicks() {
  std::ifstream stat("/proc/stat");
  std::string cpu;
  double field[8] = {};  // user nice system idle iowait irq softirq steal
  stat >> cpu;
  for (double& value : field) stat >> value;
  if (!stat || cpu != "cpu") return {0.0, 0.0};
  double all = 0.0;
  for (double value : field) all += value;
  return {field[7], all};
}

// Runs `body` as the benchmark loop and reports its time per iteration in FFT pairs measured
// just before and after it ("fft_pairs"): a figure the host's speed drift does not change, to
// compare with the targets in doc/performance.md (which are in FFT pairs). "steal_pct":
// the share of the CPUs' time the hypervisor took meanwhile (a shared virtual machine's time
// is only comparable when it is near 0).
template <typename Body>
void timeInFftPairs(benchmark::State& state, Body body) {
  const std::pair<double, double> ticks_before = cpuTicks();
  const double before = fftPairSeconds();
  const auto start = std::chrono::steady_clock::now();
  for (auto _ : state) body();
  const std::chrono::duration<double> elapsed = std::chrono::steady_clock::now() - start;
  const double yardstick = 0.5 * (before + fftPairSeconds());
  const std::pair<double, double> ticks_after = cpuTicks();
  if (state.iterations() > 0) {
    state.counters["fft_pairs"] = elapsed.count() / static_cast<double>(state.iterations()) / yardstick;
  }
  state.counters["fft_pair_ms"] = 1e3 * yardstick;
  if (ticks_after.second > ticks_before.second) {
    state.counters["steal_pct"] = 100.0 * (ticks_after.first - ticks_before.first) /
                                  (ticks_after.second - ticks_before.second);
  }
}

void BM_PairFromRawImages(benchmark::State& state) {
  oefmt::Registrar registrar(inputs().context);
  timeInFftPairs(state, [&] {
    const oefmt::FrameSpectra a = registrar.analyse(inputs().older_raw);
    const oefmt::FrameSpectra b = registrar.analyse(inputs().newer_raw);
    benchmark::DoNotOptimize(registrar.registerPair(a, b));
  });
}
BENCHMARK(BM_PairFromRawImages)->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_PairWithCachedOlder(benchmark::State& state) {
  oefmt::Registrar registrar(inputs().context);
  const oefmt::FrameSpectra a = registrar.analyse(inputs().older_raw);
  timeInFftPairs(state, [&] {
    const oefmt::FrameSpectra b = registrar.analyse(inputs().newer_raw);
    benchmark::DoNotOptimize(registrar.registerPair(a, b));
  });
}
BENCHMARK(BM_PairWithCachedOlder)->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_RegisterCachedSpectra(benchmark::State& state) {
  oefmt::Registrar registrar(inputs().context);
  const oefmt::FrameSpectra a = registrar.analyse(inputs().older);
  const oefmt::FrameSpectra b = registrar.analyse(inputs().newer);
  timeInFftPairs(state, [&] { benchmark::DoNotOptimize(registrar.registerPair(a, b)); });
}
BENCHMARK(BM_RegisterCachedSpectra)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// The same for a shift only: no warp and no forward FFT (the counter `warped` says which ran).
void BM_RegisterCachedSpectraShiftOnly(benchmark::State& state) {
  oefmt::Registrar registrar(inputs().context);
  const oefmt::FrameSpectra a = registrar.analyse(inputs().older);
  const oefmt::FrameSpectra b = registrar.analyse(inputs().shifted);
  state.counters["warped"] = registrar.registerPair(a, b).warped ? 1.0 : 0.0;
  timeInFftPairs(state, [&] { benchmark::DoNotOptimize(registrar.registerPair(a, b)); });
}
BENCHMARK(BM_RegisterCachedSpectraShiftOnly)->Unit(benchmark::kMillisecond)->MinTime(2.0);

void BM_RegisterCachedSpectraClassic(benchmark::State& state) {
  oefmt::Registrar registrar(inputs().context);
  const oefmt::FrameSpectra a = registrar.analyse(inputs().older);
  const oefmt::FrameSpectra b = registrar.analyse(inputs().newer);
  for (auto _ : state) {
    benchmark::DoNotOptimize(registrar.registerPair(a, b, oefmt::RegistrationMethod::kClassic));
  }
}
BENCHMARK(BM_RegisterCachedSpectraClassic)->Unit(benchmark::kMillisecond)->MinTime(2.0);

// The yardstick on its own: one fftPair. A shared host's speed drifts; a pair's time divided by
// this one is a figure that does not (doc/performance.md's targets are in FFT pairs).
void BM_Reference_FftPair(benchmark::State& state) {
  cv::Mat2f buffer;
  inputs().context->fft().inPlaceInput(buffer);
  for (auto _ : state) {
    fftPair(buffer);
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_Reference_FftPair)->Unit(benchmark::kMicrosecond);

// ---- Stages -------------------------------------------------------------------------------

// A 512 x 512 RGB PNG through libspng and the channel swap, as oefmt_offline reads folders;
// the texture compresses differently from camera images.
void BM_Stage_DecodePng(benchmark::State& state) {
  const std::vector<std::uint8_t>& png = inputs().older_png;
  for (auto _ : state) benchmark::DoNotOptimize(oefmt::decodeImage(png.data(), png.size()));
}
BENCHMARK(BM_Stage_DecodePng)->Unit(benchmark::kMicrosecond);

void BM_Stage_PrepareImage(benchmark::State& state) {
  for (auto _ : state) benchmark::DoNotOptimize(oefmt::prepareImage(inputs().newer_raw, kN));
}
BENCHMARK(BM_Stage_PrepareImage)->Unit(benchmark::kMicrosecond);

void BM_Stage_FrameSpectra(benchmark::State& state) {
  oefmt::SpectraBuilder builder(inputs().context);
  for (auto _ : state) benchmark::DoNotOptimize(builder.build(inputs().newer));
}
BENCHMARK(BM_Stage_FrameSpectra)->Unit(benchmark::kMicrosecond);

// As the pipeline runs: the apodized image written into the buffer, then transformed. Argument
// 0: in place (what runs); 1: into a separate image, transformed out of place.
void BM_Stage_WindowAndForwardFft(benchmark::State& state) {
  const oefmt::SpectralContext& context = *inputs().context;
  const oefmt::Fft2d& fft = context.fft();
  cv::Mat2f spectrum;
  cv::Mat1f view = fft.inPlaceInput(spectrum), separate;
  for (auto _ : state) {
    if (state.range(0) == 0) {
      context.window().apply(inputs().newer.grey, view, 0.5f);
      fft.forwardInPlace(spectrum);
    } else {
      context.window().apply(inputs().newer.grey, separate, 0.5f);
      fft.forward(separate, spectrum);
    }
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_Stage_WindowAndForwardFft)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// A cross power, then its inverse transform. Argument 0: in place (what runs); 1: out of place.
void BM_Stage_CrossPowerAndInverseFft(benchmark::State& state) {
  const oefmt::Fft2d& fft = inputs().context->fft();
  const oefmt::FrameSpectra& a = inputs().older_spectra;
  const oefmt::FrameSpectra& b = inputs().newer_spectra;
  cv::Mat2f cross_power;
  cv::Mat1f image;
  for (auto _ : state) {
    oefmt::centredCrossPower(b.spectrum, a.spectrum, cross_power);
    if (state.range(0) == 0) {
      fft.inverseInPlace(cross_power);
    } else {
      fft.inverse(cross_power, image);
    }
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_Stage_CrossPowerAndInverseFft)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

void BM_Stage_MagnitudeAndLogPolar(benchmark::State& state) {
  cv::Mat2f spectrum;
  cv::Mat1f magnitude, log_polar;  // upper half plane only: the log-polar samples no more
  inputs().context->fft().forward(inputs().newer.grey, spectrum);
  for (auto _ : state) {
    oefmt::upperHalfMagnitude(spectrum, inputs().context->highPass(), magnitude);
    inputs().context->logPolar(magnitude, log_polar);
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_Stage_MagnitudeAndLogPolar)->Unit(benchmark::kMicrosecond);

// The cross power the registrations compute (fftshift and 1/N^2 folded in).
void BM_Stage_CrossPower(benchmark::State& state) {
  const oefmt::FrameSpectra& a = inputs().older_spectra;
  const oefmt::FrameSpectra& b = inputs().newer_spectra;
  cv::Mat2f cross_power;
  for (auto _ : state) {
    oefmt::centredCrossPower(b.spectrum, a.spectrum, cross_power);
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_Stage_CrossPower)->Unit(benchmark::kMicrosecond);

void BM_Stage_HalfTurnTest(benchmark::State& state) {
  const oefmt::FrameSpectra& a = inputs().older_spectra;
  const oefmt::FrameSpectra& b = inputs().newer_spectra;
  cv::Mat2f spectrum;
  cv::Mat1f surface;
  for (auto _ : state) {
    for (bool turned : {false, true}) {
      benchmark::DoNotOptimize(oefmt::lowResolutionPeak(b.spectrum, a.spectrum, turned,
                                                        inputs().context->smallFft(), spectrum,
                                                        surface));
    }
  }
}
BENCHMARK(BM_Stage_HalfTurnTest)->Unit(benchmark::kMicrosecond);

// Argument 0: the kernel the CPU check picks (AVX2 + FMA here); 1: the portable SSE kernel.
void BM_Stage_WarpOlder(benchmark::State& state) {
  const auto kernel = state.range(0) == 0 ? oefmt::SimdKernel::kAuto : oefmt::SimdKernel::kPortable;
  cv::Mat1f warped;
  for (auto _ : state) {
    oefmt::warpSimilarityWindowed(inputs().older.grey, 0.05, 1.03, inputs().context->window(),
                                  warped, 0.0f, kernel);
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_Stage_WarpOlder)->Arg(0)->Arg(1)->Unit(benchmark::kMicrosecond);

// The same warp of a source that is not in cache, as in the pipeline (the older frame was last
// used when it was analysed): each iteration warps the next of 24 copies (24 MB).
void BM_Stage_WarpUncachedOlder(benchmark::State& state) {
  std::vector<cv::Mat1f> sources(24);
  for (cv::Mat1f& source : sources) source = inputs().older.grey.clone();
  cv::Mat1f warped;
  std::size_t next = 0;
  for (auto _ : state) {
    oefmt::warpSimilarityWindowed(sources[next], 0.05, 1.03, inputs().context->window(), warped,
                                  0.0f);
    next = (next + 1) % sources.size();
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_Stage_WarpUncachedOlder)->Unit(benchmark::kMicrosecond);

void BM_Stage_PolarUnwrapBand(benchmark::State& state) {
  cv::Mat1f polar;
  for (auto _ : state) {
    inputs().context->polarRows(inputs().newer.grey, 100, 33, polar);
    benchmark::ClobberMemory();
  }
}
BENCHMARK(BM_Stage_PolarUnwrapBand)->Unit(benchmark::kMicrosecond);

void BM_Stage_PeakAndEnergyVector(benchmark::State& state) {
  oefmt::Registrar registrar(inputs().context);
  const oefmt::FrameSpectra a = registrar.analyse(inputs().older);
  const oefmt::FrameSpectra b = registrar.analyse(inputs().newer);
  oefmt::RegistrationSurfaces surfaces;
  registrar.registerPair(a, b, oefmt::RegistrationMethod::kEnergyVectors, &surfaces);
  oefmt::EnergyVectorOptions options;
  options.row_band = 12;  // as the registration does
  for (auto _ : state) {
    // As the registration does: peak and PSR sums in one pass, then the energy vector.
    oefmt::SurfaceStats stats;
    const oefmt::SurfacePeak peak = oefmt::findPeak(surfaces.rotation_zoom, true, &stats);
    benchmark::DoNotOptimize(oefmt::extractEnergyVector(surfaces.rotation_zoom, peak, options));
    benchmark::DoNotOptimize(oefmt::peakToSidelobeRatio(surfaces.rotation_zoom, peak, stats));
  }
}
BENCHMARK(BM_Stage_PeakAndEnergyVector)->Unit(benchmark::kMicrosecond);

}  // namespace

int main(int argc, char** argv) {
  CLI::App app(
      "Time of one pair registration at N = 512 and of each of its stages (Google Benchmark; its\n"
      "own options, --benchmark_filter=REGEX and the others, are passed on to it).",
      "oefmt_benchmark");
  oefmt::tools::setUpTool(app, "Google Benchmark's options follow.");
  app.allow_extras();
  int threads = 1;
  app.add_option("--threads", threads, "OpenCV threads (default 1: FFTW is single-threaded too)")->type_name("K");
  if (const std::optional<int> exit_status = oefmt::tools::parseCommandLine(app, argc, argv)) {
    if (*exit_status != 0) return *exit_status;
    char help[] = "--help";  // Google Benchmark lists its options and exits
    char* help_argv[] = {argv[0], help, nullptr};
    int help_argc = 2;
    benchmark::Initialize(&help_argc, help_argv);
    return 0;
  }
  std::vector<std::string> rest = app.remaining();
  std::vector<char*> benchmark_argv = {argv[0]};
  for (std::string& arg : rest) benchmark_argv.push_back(arg.data());
  int benchmark_argc = static_cast<int>(benchmark_argv.size());
  benchmark_argv.push_back(nullptr);
  benchmark::Initialize(&benchmark_argc, benchmark_argv.data());
  if (benchmark::ReportUnrecognizedArguments(benchmark_argc, benchmark_argv.data())) return 1;
  oefmt::useDefaultFftWisdom();
  cv::setNumThreads(threads);
  inputs();  // plan FFTs and render the test frames before any timing starts
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
