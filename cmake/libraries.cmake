# SPDX-License-Identifier: GPL-3.0-or-later
# The ROS-free libraries, one per layer, each depending only on the ones above it:
#   oefmt_registration  spectra, FFT, warps, phase correlation, energy vectors, pattern matching
#   oefmt_estimation    pair motion, local optimizer, pose integration, the estimator
#   oefmt_io            configuration files, image files, dataset folders, undistortion
#   oefmt_evaluation    TUM trajectories against ground truth (association, alignment, errors)
#   oefmt_sim           the flight simulator's scenes, textures and renderer
# Included by CMakeLists.txt and by fuzz/CMakeLists.txt, so the fuzzers and the sanitizer build
# compile the very targets the package ships. Expects OEFMT_ROOT and the packages found by the
# includer; OEFMT_LIBRARY_OPTIONS adds compile options to every one of these libraries.

function(oefmt_layer_library name folder)
  file(GLOB sources CONFIGURE_DEPENDS ${OEFMT_ROOT}/src/${folder}/*.cpp)
  add_library(${name} ${sources})
  target_include_directories(${name} PUBLIC $<BUILD_INTERFACE:${OEFMT_ROOT}/include>)
  target_include_directories(${name} SYSTEM PUBLIC ${OpenCV_INCLUDE_DIRS})
  # errno is never read: lets sqrt vectorise in the per-frequency loops;
  # -fopenmp-simd: honour `#pragma omp simd` (vectorised reductions) without OpenMP threads.
  target_compile_options(${name} PRIVATE -fno-math-errno -fopenmp-simd ${OEFMT_LIBRARY_OPTIONS})
endfunction()

oefmt_layer_library(oefmt_registration registration)
# CPU-specific kernels, called only after a run-time CPU check (see
# src/registration/simd_kernels.h). Elsewhere (ARM) those files compile to stubs never called.
if(CMAKE_SYSTEM_PROCESSOR MATCHES "x86_64|AMD64")
  file(GLOB OEFMT_AVX2_SOURCES CONFIGURE_DEPENDS ${OEFMT_ROOT}/src/registration/*_avx2.cpp)
  set_source_files_properties(${OEFMT_AVX2_SOURCES} PROPERTIES COMPILE_OPTIONS "-mavx2;-mfma")
endif()
target_link_libraries(oefmt_registration PUBLIC opencv_core opencv_imgproc PRIVATE PkgConfig::FFTW3F)

oefmt_layer_library(oefmt_estimation estimation)
target_link_libraries(oefmt_estimation PUBLIC oefmt_registration Eigen3::Eigen Ceres::ceres)

oefmt_layer_library(oefmt_io io)
# libspng decodes PNG files (libdeflate inflates the fast path's 8-bit colour ones, see
# src/io/png_decoders.h), OpenCV's imgcodecs the other formats (src/io/image_decoding.cpp);
# yaml-cpp reads the configuration file and cam_param.yaml (src/io/yaml_document.h).
target_link_libraries(oefmt_io PUBLIC oefmt_estimation opencv_calib3d
                               PRIVATE opencv_imgcodecs PkgConfig::SPNG PkgConfig::LIBDEFLATE yaml-cpp)

oefmt_layer_library(oefmt_evaluation evaluation)
target_link_libraries(oefmt_evaluation PUBLIC oefmt_io Eigen3::Eigen)

oefmt_layer_library(oefmt_sim sim)
target_link_libraries(oefmt_sim PUBLIC oefmt_io)
