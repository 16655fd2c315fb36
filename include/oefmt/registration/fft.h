// SPDX-License-Identifier: GPL-3.0-or-later
// Square 2-D real FFTs through FFTW3 single precision, planned once per size.
#pragma once

#include <complex>
#include <memory>
#include <string>

#include <opencv2/core.hpp>

#include "oefmt/enum_names.h"

namespace oefmt {

using Complex = std::complex<float>;

/// How long FFTW may search for a fast plan when an Fft2d is made (once per size and machine:
/// measured plans are kept as wisdom, see setFftWisdomFile). kPatient plans take several
/// times as long as kMeasure's to make and ran faster (doc/performance.md), which pays off
/// from the first run on, as the wisdom keeps them.
enum class FftPlanning { kEstimate, kMeasure, kPatient };
/// The configuration's spelling of each effort.
inline constexpr EnumName<FftPlanning> kFftPlanningNames[] = {
    {FftPlanning::kEstimate, "estimate"}, {FftPlanning::kMeasure, "measure"}, {FftPlanning::kPatient, "patient"}};
inline const char* toString(FftPlanning planning) { return enumName(kFftPlanningNames, planning); }

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

  /// In-place transforms (FFTW's out-of-place 2-D real plans copy through a buffer; in place
  /// they do not). A size x (size/2 + 1) complex buffer holds the spectrum; its realView()
  /// (size x size floats, rows padded to the buffer's stride) holds the image.
  /// The image to write before forwardInPlace: `buffer` allocated if it has the wrong shape,
  /// and its realView().
  cv::Mat1f inPlaceInput(cv::Mat2f& buffer) const;
  /// realView(buffer) -> buffer = FFT(image).
  void forwardInPlace(cv::Mat2f& buffer) const;
  /// buffer -> realView(buffer) = IFFT(spectrum) * size^2.
  void inverseInPlace(cv::Mat2f& buffer) const;
  /// The image rows inside an in-place buffer (shares its memory; not continuous).
  cv::Mat1f realView(cv::Mat2f& buffer) const;

 private:
  void makeOutOfPlacePlans() const;
  void requireInPlaceBuffer(const cv::Mat2f& buffer, const char* what) const;

  struct Plans;
  int size_;
  std::unique_ptr<Plans> plans_;
};

/// FFTW wisdom (what FFTW_MEASURE learnt about fast plans on this machine), kept between runs:
/// measuring the plans would otherwise cost time at every start. Once a file is set, the first
/// measured Fft2d imports it; a new measurement is exported back to it (written to a temporary
/// file, then renamed). Failures only cost the speed-up. The library keeps no file unless told
/// ("", the default): the tools and the node set the user's cache file (oefmt/io/fft_wisdom.h).
void setFftWisdomFile(const std::string& path);
/// The file set by setFftWisdomFile ("" = none).
std::string fftWisdomFile();
/// Replaces the process's FFTW wisdom with the file's; false (wisdom forgotten) if unreadable.
bool importFftWisdom(const std::string& path);
/// Writes the process's FFTW wisdom to `path` atomically; false on failure.
bool exportFftWisdom(const std::string& path);
/// Whether an Fft2d(size, planning) would find its plans in the wisdom (importing the wisdom
/// file first, as Fft2d does): false means it is about to measure them, which
/// a caller may want to announce (seconds at N = 512 with kPatient). kEstimate: always true.
bool fftPlansKnown(int size, FftPlanning planning);

/// View of a spectrum's elements as std::complex<float>.
inline Complex* complexData(cv::Mat2f& spectrum) { return reinterpret_cast<Complex*>(spectrum.data); }
inline const Complex* complexData(const cv::Mat2f& spectrum) {
  return reinterpret_cast<const Complex*>(spectrum.data);
}

}  // namespace oefmt
