// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/registration/spectra.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <string>
#include <vector>

#include <opencv2/imgproc.hpp>

#include "oefmt/error.h"
#include "simd_kernels.h"

namespace oefmt {
namespace {

// Largest |intensity| whose spectra stay accurate in single precision at any working size.
constexpr double kMaxSpectralIntensity = 1024.0;

// H = 1 - cos^2(|X|) with X sampled so that DC (N/2, N/2) is exactly 0 and the edge is pi/2.
cv::Mat1f makeHighPass(int n) {
  cv::Mat1f filter(n / 2 + 2, n);  // the half plane the log-polar samples
  for (int r = 0; r < filter.rows; ++r) {
    const double y = (r - n / 2) * CV_PI / n;
    for (int c = 0; c < n; ++c) {
      const double x = (c - n / 2) * CV_PI / n;
      const double cosine = std::cos(std::sqrt(x * x + y * y));
      filter(r, c) = static_cast<float>(1.0 - cosine * cosine);
    }
  }
  return filter;
}

// One row of a polar or log-polar unwrap: `source` (rows may be padded) sampled bilinearly at
// (N/2, N/2) + t_c (dx, dy), t_c = positions[c] (or c when null), for the source's N columns;
// zero outside.
void sampleRay(const cv::Mat1f& source, float dx, float dy, const float* positions, float* out,
               bool avx2) {
  detail::LineSamples ray{};
  ray.source = source.ptr<float>();
  ray.stride = static_cast<int>(source.step1());
  ray.cols = source.cols;
  ray.rows = source.rows;
  ray.sx0 = ray.sy0 = static_cast<float>(source.cols / 2);
  ray.dx = dx;
  ray.dy = dy;
  ray.positions = positions;
  ray.row_weight = 1.0f;
  ray.count = source.cols;
  ray.out = out;
  detail::sampleLine(ray, avx2);
}

}  // namespace

SpectralContext::SpectralContext(const RegistrationConfig& config)
    : config_((config.validate(), config)),
      fft_(config.size, config.fft_planning),
      window_(config.size, config.taper_fraction),
      high_pass_(makeHighPass(config.size)),
      log_polar_base_(std::pow(config.logpolar_radius_fraction * config.size, 1.0 / config.size)),
      polar_radius_step_(config.polar_radius_fraction),
      small_fft_(std::min(128, config.size / 2), config.fft_planning) {
  // Rows span exactly pi (the magnitude is point-symmetric), so the row axis is cyclic. Angles
  // 0..-pi only reach the upper half plane: rows 0..N/2 (+1 for the bilinear neighbour).
  const int n = config.size;
  log_polar_cos_.resize(n);
  log_polar_sin_.resize(n);
  log_polar_radii_.resize(n);
  for (int i = 0; i < n; ++i) {
    const double angle = -CV_PI * i / n;
    log_polar_cos_[i] = static_cast<float>(std::cos(angle));
    log_polar_sin_[i] = static_cast<float>(std::sin(angle));
    log_polar_radii_[i] = static_cast<float>(std::pow(log_polar_base_, i));
  }
}

void SpectralContext::logPolar(const cv::Mat1f& upper_half_magnitude, cv::Mat1f& out,
                               SimdKernel kernel) const {
  const int n = config_.size;
  if (upper_half_magnitude.rows != n / 2 + 2 || upper_half_magnitude.cols != n) {
    throw InputError("logPolar: magnitude of the wrong size");
  }
  out.create(n, n);
  const bool avx2 = detail::runsAvx2(kernel);
  for (int i = 0; i < n; ++i) {
    sampleRay(upper_half_magnitude, log_polar_cos_[i], log_polar_sin_[i], log_polar_radii_.data(),
              out[i], avx2);
  }
}

void SpectralContext::polarRows(const cv::Mat1f& centred_surface, int first_row, int count,
                                cv::Mat1f& out, SimdKernel kernel) const {
  const int n = config_.size;
  if (centred_surface.rows != n || centred_surface.cols != n) {
    throw InputError("polarRows: surface of the wrong size");
  }
  out.create(count, n);
  const bool avx2 = detail::runsAvx2(kernel);
  for (int i = 0; i < count; ++i) {
    // Zero outside the surface (no cyclic wrap: radii beyond N/2 are not aliases).
    const double direction = 2.0 * CV_PI * (first_row + i) / n;
    sampleRay(centred_surface, static_cast<float>(polar_radius_step_ * std::cos(direction)),
              static_cast<float>(polar_radius_step_ * std::sin(direction)), nullptr, out[i], avx2);
  }
}

void upperHalfMagnitude(const cv::Mat2f& spectrum, const cv::Mat1f& filter, cv::Mat1f& magnitude,
                        SimdKernel kernel) {
  const int n = spectrum.rows;
  const int half = n / 2;
  magnitude.create(half + 2, n);
  const bool avx2 = detail::runsAvx2(kernel);
  // |.| of the half + 1 stored columns of the two spectrum rows a centred row needs.
  std::vector<float> direct(half + 1), mirror(half + 1);
  auto magnitudes = [avx2](const float* complex_values, int count, float* out) {
    if (avx2) {
      detail::magnitudeRowAvx2(complex_values, count, out);
      return;
    }
#pragma omp simd
    for (int i = 0; i < count; ++i) {
      const float re = complex_values[2 * i], im = complex_values[2 * i + 1];
      out[i] = std::sqrt(re * re + im * im);
    }
  };
  for (int row = 0; row < half + 2; ++row) {
    // Centred row `row` holds frequency fy = row - N/2; columns with fx >= 0 come from spectrum
    // row fy mod N, columns with fx < 0 from the conjugate at (-fx, -fy).
    const int fy = row - half;
    magnitudes(spectrum.ptr<float>(((fy % n) + n) % n), half + 1, direct.data());
    magnitudes(spectrum.ptr<float>(((-fy % n) + n) % n), half + 1, mirror.data());
    const float* h = filter[row];
    float* out = magnitude[row];
    for (int col = half; col < n; ++col) out[col] = direct[col - half] * h[col];
    for (int col = 0; col < half; ++col) out[col] = mirror[half - col] * h[col];
  }
}

float noisePower(const cv::Mat2f& spectrum) {
  const int n = spectrum.rows;
  const int cols = spectrum.cols;
  const double inner = 0.4 * n;
  // Every third frequency of every third row is plenty for a quartile (thousands of values).
  constexpr int kStride = 3;
  std::vector<float> ring;
  ring.reserve(static_cast<std::size_t>(n) * cols / (kStride * kStride));
  for (int row = 0; row < n; row += kStride) {
    const double fy = row < n / 2 ? row : row - n;
    const float* values = spectrum.ptr<float>(row);
    const int first = fy * fy >= inner * inner ? 0 : static_cast<int>(std::ceil(std::sqrt(inner * inner - fy * fy)));
    for (int col = first; col < cols; col += kStride) {
      const float re = values[2 * col], im = values[2 * col + 1];
      const float power = re * re + im * im;
      if (std::isfinite(power)) ring.push_back(power);
    }
  }
  if (ring.empty()) return 0.0f;
  const auto quartile = ring.begin() + ring.size() / 4;
  std::nth_element(ring.begin(), quartile, ring.end());
  // The lower quartile of an exponential distribution is ln(4/3) times its mean.
  return static_cast<float>(*quartile / std::log(4.0 / 3.0));
}

std::string fftPlanningNotice(const RegistrationConfig& config) {
  if (fftPlansKnown(config.size, config.fft_planning)) return std::string();
  const std::string n = std::to_string(config.size);
  const std::string wisdom = fftWisdomFile();
  return "measuring FFTW plans for " + n + "x" + n + " transforms (registration.fft_planning: " +
         toString(config.fft_planning) + "; at N = 512 about 1 s with measure, 10 s with patient)" +
         (wisdom.empty() ? std::string(", at every start: no wisdom file is kept")
                         : ", once: they are kept in " + wisdom);
}

SpectraBuilder::SpectraBuilder(std::shared_ptr<const SpectralContext> context)
    : context_(std::move(context)) {
  if (!context_) throw InputError("SpectraBuilder: null context");
}

FrameSpectra SpectraBuilder::build(const PreparedImage& image) {
  const int n = context_->size();
  if (image.grey.rows != n || image.grey.cols != n) {
    throw InputError("prepared image is " + std::to_string(image.grey.cols) + "x" +
                     std::to_string(image.grey.rows) + ", expected " + std::to_string(n) + "x" +
                     std::to_string(n));
  }
  if (!image.seen.empty() && image.seen.size() != image.grey.size()) {
    throw InputError("prepared image: the mask of what the camera saw is " + std::to_string(image.seen.cols) + "x" +
                     std::to_string(image.seen.rows) + ", the image " + std::to_string(n) + "x" + std::to_string(n));
  }
  FrameSpectra frame;
  frame.grey = image.grey.isContinuous() ? image.grey : image.grey.clone();
  // Float frames keep their values, and single-precision spectra overflow (or the normalised
  // cross power drops frequencies) far below FLT_MAX: scale such frames down. Every correlation
  // is normalised, so a frame's intensity scale does not change its registration.
  double largest = image.largest_magnitude;
  if (std::isnan(largest)) {
    double low = 0.0, high = 0.0;
    cv::minMaxLoc(frame.grey, &low, &high);
    largest = std::max(-low, high);
  }
  bool scaled_down = false;
  if (largest > kMaxSpectralIntensity && std::isfinite(largest)) {
    cv::Mat1f scaled;  // a new buffer: frame.grey may share the caller's pixels
    frame.grey.convertTo(scaled, CV_32F, kMaxSpectralIntensity / largest);
    frame.grey = scaled;
    scaled_down = true;
  }
  frame.texture = image.texture;
  frame.invalid_pixels = image.invalid_pixels;
  const bool mean_known = !std::isnan(image.mean) && !scaled_down;
  frame.mean = static_cast<float>(mean_known ? image.mean : cv::mean(frame.grey)[0]);
  // Both images are written straight into their spectra's buffers (in-place FFTs).
  const Fft2d& fft = context_->fft();
  cv::Mat1f windowed = fft.inPlaceInput(frame.spectrum);
  context_->window().apply(frame.grey, windowed, frame.mean);
  fft.forwardInPlace(frame.spectrum);
  if (context_->config().noise_weighting) frame.noise_power = noisePower(frame.spectrum);
  if (context_->config().refine_zoom) {
    // White noise of variance v has |.|^2 = v sum(w^2) at every frequency of the apodized image's
    // spectrum (w the separable window).
    double taper_energy = 0.0;
    for (const float t : context_->window().taper()) taper_energy += static_cast<double>(t) * t;
    const double noise_variance =
        taper_energy > 0.0 ? frame.noise_power / (taper_energy * taper_energy) : 0.0;
    frame.refinement = makeRefinementImage(frame.grey, noise_variance, image.seen);
  }
  upperHalfMagnitude(frame.spectrum, context_->highPass(), magnitude_);
  cv::Mat1f log_polar = fft.inPlaceInput(frame.log_polar_spectrum);
  context_->logPolar(magnitude_, log_polar);
  fft.forwardInPlace(frame.log_polar_spectrum);
  static std::atomic<std::uint64_t> next_serial{1};
  frame.serial = next_serial.fetch_add(1);
  if (lookback_ > 0) {
    // One more than the lookback: the frame built last is among them.
    recent_.push_back({frame.serial, frame.log_polar_spectrum});
    if (static_cast<int>(recent_.size()) > lookback_ + 1) recent_.erase(recent_.begin());
  }
  return frame;
}

void SpectraBuilder::setLookback(int frames) {
  lookback_ = std::max(frames, 0);
  const std::size_t keep = lookback_ > 0 ? static_cast<std::size_t>(lookback_) + 1 : 0;
  while (recent_.size() > keep) recent_.erase(recent_.begin());
}

void SpectraBuilder::correlateWithRecent(FrameSpectra& frame) const {
  if (recent_.empty() || recent_.back().serial != frame.serial) return;  // not the frame built last
  for (std::size_t i = 0; i + 1 < recent_.size(); ++i) {
    RotationZoomCorrelation c;
    c.older_serial = recent_[i].serial;
    correlateRotationZoom(*context_, frame.log_polar_spectrum, recent_[i].log_polar_spectrum, c);
    frame.correlated.push_back(std::move(c));
  }
}

void correlateRotationZoom(const SpectralContext& context, const cv::Mat2f& newer, const cv::Mat2f& older,
                           RotationZoomCorrelation& out) {
  centredCrossPower(newer, older, out.power);
  context.fft().inverseInPlace(out.power);
  out.highest = findPeak(context.fft().realView(out.power), true, &out.stats, PeakShape::kBroadened);
}

FrameSpectra SpectraBuilder::build(const cv::Mat& image, ChannelOrder order) {
  return build(prepareImage(image, context_->size(), order));
}

}  // namespace oefmt
