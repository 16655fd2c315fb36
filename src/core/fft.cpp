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
  fftwf_plan inverse_columns = nullptr;  // 1-D c2c along each column, in place
  fftwf_plan inverse_row = nullptr;      // 1-D c2r of one row
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
  const int length = size;
  plans_->inverse_columns = fftwf_plan_many_dft(
      1, &length, spectrumCols(), reinterpret_cast<fftwf_complex*>(spectrum.data), nullptr,
      spectrumCols(), 1, reinterpret_cast<fftwf_complex*>(spectrum.data), nullptr, spectrumCols(),
      1, FFTW_BACKWARD, flags);
  plans_->inverse_row = fftwf_plan_dft_c2r_1d(
      size, reinterpret_cast<fftwf_complex*>(spectrum.data), image.ptr<float>(), flags);
  if (plans_->forward == nullptr || plans_->inverse == nullptr ||
      plans_->inverse_columns == nullptr || plans_->inverse_row == nullptr) {
    throw std::runtime_error("Fft2d: FFTW could not plan a " + std::to_string(size) + "^2 FFT");
  }
}

Fft2d::~Fft2d() {
  std::lock_guard<std::mutex> lock(plannerMutex());
  if (plans_->forward != nullptr) fftwf_destroy_plan(plans_->forward);
  if (plans_->inverse != nullptr) fftwf_destroy_plan(plans_->inverse);
  if (plans_->inverse_columns != nullptr) fftwf_destroy_plan(plans_->inverse_columns);
  if (plans_->inverse_row != nullptr) fftwf_destroy_plan(plans_->inverse_row);
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

void Fft2d::inverseColumns(cv::Mat2f& spectrum) const {
  if (spectrum.rows != size_ || spectrum.cols != spectrumCols() || !spectrum.isContinuous()) {
    throw InputError("Fft2d::inverseColumns: spectrum has the wrong shape");
  }
  requireAligned(spectrum.data, "spectrum");
  fftwf_execute_dft(plans_->inverse_columns, reinterpret_cast<fftwf_complex*>(spectrum.data),
                    reinterpret_cast<fftwf_complex*>(spectrum.data));
}

void Fft2d::inverseRows(const cv::Mat2f& column_transformed, int first_row, int count,
                        cv::Mat1f& out) const {
  if (column_transformed.rows != size_ || column_transformed.cols != spectrumCols() ||
      count < 1 || count > size_) {
    throw InputError("Fft2d::inverseRows: bad spectrum shape or row count");
  }
  out.create(count, size_);
  // Rows of the spectrum are 8 * (N/2 + 1) bytes apart, not SIMD-aligned: go through aligned
  // copies (c2r overwrites its input anyway).
  cv::Mat2f row(1, spectrumCols());
  cv::Mat1f row_out(1, size_);
  for (int i = 0; i < count; ++i) {
    const int source_row = ((first_row + i) % size_ + size_) % size_;
    column_transformed.row(source_row).copyTo(row);
    fftwf_execute_dft_c2r(plans_->inverse_row, reinterpret_cast<fftwf_complex*>(row.data),
                          row_out.ptr<float>());
    row_out.copyTo(out.row(i));
  }
}

}  // namespace oefmt
