// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/fft.h"

#include <fftw3.h>

#include <mutex>
#include <string>

#include "oefmt/error.h"

namespace oefmt {
namespace {

// FFTW's planner is not thread-safe (plan execution is); every plan is made and destroyed
// under this lock.
std::mutex& plannerMutex() {
  static std::mutex mutex;
  return mutex;
}

void requireAligned(const void* data, const char* what) {
  // Plans are made on freshly allocated (maximally aligned) arrays; OpenCV allocates 64-byte
  // aligned blocks, so a continuous cv::Mat always matches.
  if (fftwf_alignment_of(reinterpret_cast<float*>(const_cast<void*>(data))) != 0) {
    throw std::logic_error(std::string("Fft2d: ") + what + " is not SIMD-aligned");
  }
}

}  // namespace

struct Fft2d::Plans {
  fftwf_plan forward = nullptr;
  fftwf_plan inverse = nullptr;
};

Fft2d::Fft2d(int size, FftPlanning planning) : size_(size), plans_(std::make_unique<Plans>()) {
  if (size < 2 || size % 2 != 0) {
    throw InputError("Fft2d: size must be even and >= 2, got " + std::to_string(size));
  }
  const unsigned flags = planning == FftPlanning::kMeasure ? FFTW_MEASURE : FFTW_ESTIMATE;
  cv::Mat1f image(size, size);
  cv::Mat2f spectrum(size, spectrumCols());
  std::lock_guard<std::mutex> lock(plannerMutex());
  plans_->forward = fftwf_plan_dft_r2c_2d(size, size, image.ptr<float>(),
                                          reinterpret_cast<fftwf_complex*>(spectrum.data), flags);
  plans_->inverse = fftwf_plan_dft_c2r_2d(size, size,
                                          reinterpret_cast<fftwf_complex*>(spectrum.data),
                                          image.ptr<float>(), flags);
  if (plans_->forward == nullptr || plans_->inverse == nullptr) {
    throw std::runtime_error("Fft2d: FFTW could not plan a " + std::to_string(size) + "^2 FFT");
  }
}

Fft2d::~Fft2d() {
  std::lock_guard<std::mutex> lock(plannerMutex());
  if (plans_->forward != nullptr) fftwf_destroy_plan(plans_->forward);
  if (plans_->inverse != nullptr) fftwf_destroy_plan(plans_->inverse);
}

void Fft2d::forward(const cv::Mat1f& image, cv::Mat2f& spectrum) const {
  if (image.rows != size_ || image.cols != size_ || !image.isContinuous()) {
    throw InputError("Fft2d::forward: expected a continuous " + std::to_string(size_) + "x" +
                     std::to_string(size_) + " float image");
  }
  spectrum.create(size_, spectrumCols());
  requireAligned(image.data, "input image");
  requireAligned(spectrum.data, "spectrum");
  // r2c out-of-place preserves its input, so dropping const is safe.
  fftwf_execute_dft_r2c(plans_->forward, const_cast<float*>(image.ptr<float>()),
                        reinterpret_cast<fftwf_complex*>(spectrum.data));
}

void Fft2d::inverse(cv::Mat2f& spectrum, cv::Mat1f& image) const {
  if (spectrum.rows != size_ || spectrum.cols != spectrumCols() || !spectrum.isContinuous()) {
    throw InputError("Fft2d::inverse: spectrum has the wrong shape");
  }
  image.create(size_, size_);
  requireAligned(image.data, "output image");
  requireAligned(spectrum.data, "spectrum");
  fftwf_execute_dft_c2r(plans_->inverse, reinterpret_cast<fftwf_complex*>(spectrum.data),
                        image.ptr<float>());
}

}  // namespace oefmt
