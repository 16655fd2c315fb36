// SPDX-License-Identifier: GPL-3.0-or-later
// Square 2-D real FFTs through FFTW3 single precision, planned once per size.
#pragma once

#include <complex>
#include <memory>

#include <opencv2/core.hpp>

namespace oefmt {

using Complex = std::complex<float>;

/// How long FFTW may search for a fast plan when an Fft2d is made (once per size).
enum class FftPlanning { kEstimate, kMeasure };

/// Forward (real -> half spectrum) and inverse (half spectrum -> real) transforms of
/// size x size images. Plans are made once in the constructor; execution is thread-safe, so one
/// instance can be shared by several threads. Spectra are size rows x (size/2 + 1) columns of
/// CV_32FC2 (one std::complex<float> per element). Transforms are unnormalised.
class Fft2d {
 public:
  Fft2d(int size, FftPlanning planning);
  ~Fft2d();
  Fft2d(const Fft2d&) = delete;
  Fft2d& operator=(const Fft2d&) = delete;

  int size() const { return size_; }
  int spectrumCols() const { return size_ / 2 + 1; }

  /// spectrum = FFT(image). image must be size x size CV_32FC1 and continuous.
  void forward(const cv::Mat1f& image, cv::Mat2f& spectrum) const;
  /// image = IFFT(spectrum) * size^2 (unnormalised). spectrum is overwritten (FFTW c2r).
  void inverse(cv::Mat2f& spectrum, cv::Mat1f& image) const;

 private:
  struct Plans;
  int size_;
  std::unique_ptr<Plans> plans_;
};

/// View of a spectrum's elements as std::complex<float>.
inline Complex* complexData(cv::Mat2f& spectrum) { return reinterpret_cast<Complex*>(spectrum.data); }
inline const Complex* complexData(const cv::Mat2f& spectrum) {
  return reinterpret_cast<const Complex*>(spectrum.data);
}

}  // namespace oefmt
