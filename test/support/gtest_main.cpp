// SPDX-License-Identifier: GPL-3.0-or-later
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "oefmt/io/fft_wisdom.h"

int main(int argc, char** argv) {
  // Tests plan FFTs in their own wisdom file, never in the user's (~/.cache/oefmt): plans
  // measured while the tests load the machine (and re-measured after a test forgets the
  // wisdom on purpose) would otherwise replace the ones the user's runs measured.
  if (std::getenv("OEFMT_FFTW_WISDOM") == nullptr) {
    std::error_code error;
    const std::filesystem::path temporary = std::filesystem::temp_directory_path(error);
    const std::string wisdom =
        error ? std::string("none")
              : (temporary / ("oefmt-tests-fftwf-wisdom-" + std::to_string(::getuid()))).string();
    setenv("OEFMT_FFTW_WISDOM", wisdom.c_str(), 1);
  }
  oefmt::useDefaultFftWisdom();
  ::testing::InitGoogleTest(&argc, argv);
  return RUN_ALL_TESTS();
}
