// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/registration/fft.h"

#include <fftw3.h>

#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <filesystem>
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

// The wisdom file (setFftWisdomFile) and whether it has been read; guarded by the planner mutex.
std::string& wisdomFile() {
  static std::string path;
  return path;
}
bool& wisdomImported() {
  static bool imported = false;
  return imported;
}

// Measuring plans for which the wisdom had no answer takes this long at least; quicker
// planning means the wisdom was used and there is nothing new to save.
constexpr double kNewWisdomSeconds = 0.02;

bool importWisdomLocked(const std::string& path) {
  if (path.empty() || !std::filesystem::is_regular_file(path)) return false;
  if (fftwf_import_wisdom_from_filename(path.c_str()) != 0) return true;
  fftwf_forget_wisdom();  // a damaged file must not leave half its plans behind
  return false;
}

bool exportWisdomLocked(const std::string& path) {
  if (path.empty()) return false;
  std::error_code error;
  const std::filesystem::path target(path);
  if (target.has_parent_path()) std::filesystem::create_directories(target.parent_path(), error);
  // Several processes may save at once: each writes its own file and renames it into place.
  const std::string temporary = path + ".tmp" + std::to_string(::getpid());
  if (fftwf_export_wisdom_to_filename(temporary.c_str()) == 0) {
    std::remove(temporary.c_str());
    return false;
  }
  std::filesystem::rename(temporary, target, error);
  if (error) std::remove(temporary.c_str());
  return !error;
}

}  // namespace

void setFftWisdomFile(const std::string& path) {
  std::lock_guard<std::mutex> lock(plannerMutex());
  wisdomFile() = path;
  wisdomImported() = false;
}

std::string fftWisdomFile() {
  std::lock_guard<std::mutex> lock(plannerMutex());
  return wisdomFile();
}

namespace {

unsigned plannerFlags(FftPlanning planning) {
  switch (planning) {
    case FftPlanning::kEstimate: return FFTW_ESTIMATE;
    case FftPlanning::kMeasure: return FFTW_MEASURE;
    case FftPlanning::kPatient: return FFTW_PATIENT;
  }
  return FFTW_MEASURE;
}

// The first measured Fft2d (or fftPlansKnown) after the wisdom file is set reads it once; later
// ones find its plans in memory. The caller holds the planner mutex.
void importWisdomOnceLocked(FftPlanning planning) {
  if (wisdomImported() || planning == FftPlanning::kEstimate) return;
  if (wisdomFile().empty()) return;
  importWisdomLocked(wisdomFile());
  wisdomImported() = true;
}

// Plans the r2c and c2r transforms between `real` and `complex` (the same memory: in place) and
// saves the wisdom when it had to be measured. The caller holds the planner mutex.
void planPairLocked(int size, float* real, fftwf_complex* complex, FftPlanning planning,
                    fftwf_plan& forward, fftwf_plan& inverse) {
  const unsigned flags = plannerFlags(planning);
  const std::string wisdom = planning == FftPlanning::kEstimate ? std::string() : wisdomFile();
  const auto start = std::chrono::steady_clock::now();
  forward = fftwf_plan_dft_r2c_2d(size, size, real, complex, flags);
  inverse = fftwf_plan_dft_c2r_2d(size, size, complex, real, flags);
  if (forward == nullptr || inverse == nullptr) {
    throw std::runtime_error("Fft2d: FFTW could not plan a " + std::to_string(size) + "^2 FFT");
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!wisdom.empty() && seconds > kNewWisdomSeconds) exportWisdomLocked(wisdom);
}

}  // namespace

bool importFftWisdom(const std::string& path) {
  std::lock_guard<std::mutex> lock(plannerMutex());
  return importWisdomLocked(path);
}

bool exportFftWisdom(const std::string& path) {
  std::lock_guard<std::mutex> lock(plannerMutex());
  return exportWisdomLocked(path);
}

bool fftPlansKnown(int size, FftPlanning planning) {
  if (planning == FftPlanning::kEstimate) return true;
  if (size < 2 || size % 2 != 0) return false;
  cv::Mat2f spectrum(size, size / 2 + 1);  // aligned like the buffers Fft2d plans on
  float* real = reinterpret_cast<float*>(spectrum.data);
  auto* complex = reinterpret_cast<fftwf_complex*>(spectrum.data);
  std::lock_guard<std::mutex> lock(plannerMutex());
  importWisdomOnceLocked(planning);
  const unsigned flags = plannerFlags(planning) | FFTW_WISDOM_ONLY;
  bool known = true;
  for (fftwf_plan plan : {fftwf_plan_dft_r2c_2d(size, size, real, complex, flags),
                          fftwf_plan_dft_c2r_2d(size, size, complex, real, flags)}) {
    known = known && plan != nullptr;
    if (plan != nullptr) fftwf_destroy_plan(plan);
  }
  return known;
}

struct Fft2d::Plans {
  fftwf_plan forward_in_place = nullptr;
  fftwf_plan inverse_in_place = nullptr;
  // Out-of-place plans are made on first use: the pipeline runs in place, and planning them
  // without wisdom costs about a second at N = 512.
  std::once_flag out_of_place_made;
  fftwf_plan forward = nullptr;
  fftwf_plan inverse = nullptr;
  FftPlanning planning = FftPlanning::kMeasure;
};

Fft2d::Fft2d(int size, FftPlanning planning) : size_(size), plans_(std::make_unique<Plans>()) {
  if (size < 2 || size % 2 != 0) {
    throw InputError("Fft2d: size must be even and >= 2, got " + std::to_string(size));
  }
  cv::Mat2f spectrum(size, spectrumCols());
  std::lock_guard<std::mutex> lock(plannerMutex());
  importWisdomOnceLocked(planning);
  plans_->planning = planning;
  planPairLocked(size, reinterpret_cast<float*>(spectrum.data),
                 reinterpret_cast<fftwf_complex*>(spectrum.data), planning,
                 plans_->forward_in_place, plans_->inverse_in_place);
}

void Fft2d::makeOutOfPlacePlans() const {
  std::call_once(plans_->out_of_place_made, [this] {
    cv::Mat1f image(size_, size_);
    cv::Mat2f spectrum(size_, spectrumCols());
    std::lock_guard<std::mutex> lock(plannerMutex());
    planPairLocked(size_, image.ptr<float>(), reinterpret_cast<fftwf_complex*>(spectrum.data),
                   plans_->planning, plans_->forward, plans_->inverse);
  });
}

Fft2d::~Fft2d() {
  std::lock_guard<std::mutex> lock(plannerMutex());
  for (fftwf_plan plan : {plans_->forward, plans_->inverse, plans_->forward_in_place,
                          plans_->inverse_in_place}) {
    if (plan != nullptr) fftwf_destroy_plan(plan);
  }
}

void Fft2d::forward(const cv::Mat1f& image, cv::Mat2f& spectrum) const {
  if (image.rows != size_ || image.cols != size_ || !image.isContinuous()) {
    throw InputError("Fft2d::forward: expected a continuous " + std::to_string(size_) + "x" +
                     std::to_string(size_) + " float image");
  }
  spectrum.create(size_, spectrumCols());
  makeOutOfPlacePlans();
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
  makeOutOfPlacePlans();
  requireAligned(image.data, "output image");
  requireAligned(spectrum.data, "spectrum");
  fftwf_execute_dft_c2r(plans_->inverse, reinterpret_cast<fftwf_complex*>(spectrum.data),
                        image.ptr<float>());
}

cv::Mat1f Fft2d::inPlaceInput(cv::Mat2f& buffer) const {
  buffer.create(size_, spectrumCols());
  return realView(buffer);
}

void Fft2d::requireInPlaceBuffer(const cv::Mat2f& buffer, const char* what) const {
  if (buffer.rows != size_ || buffer.cols != spectrumCols() || !buffer.isContinuous()) {
    throw InputError(std::string("Fft2d::") + what + ": not an in-place buffer of size " +
                     std::to_string(size_));
  }
  requireAligned(buffer.data, what);
}

cv::Mat1f Fft2d::realView(cv::Mat2f& buffer) const {
  requireInPlaceBuffer(buffer, "realView");
  return cv::Mat1f(size_, size_, buffer.ptr<float>(), buffer.step);
}

void Fft2d::forwardInPlace(cv::Mat2f& buffer) const {
  requireInPlaceBuffer(buffer, "forwardInPlace");
  fftwf_execute_dft_r2c(plans_->forward_in_place, buffer.ptr<float>(),
                        reinterpret_cast<fftwf_complex*>(buffer.data));
}

void Fft2d::inverseInPlace(cv::Mat2f& buffer) const {
  requireInPlaceBuffer(buffer, "inverseInPlace");
  fftwf_execute_dft_c2r(plans_->inverse_in_place, reinterpret_cast<fftwf_complex*>(buffer.data),
                        buffer.ptr<float>());
}

}  // namespace oefmt
