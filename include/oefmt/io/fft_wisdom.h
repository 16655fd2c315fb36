// SPDX-License-Identifier: GPL-3.0-or-later
// Where the tools and the node keep FFTW's wisdom between runs (the registration library itself
// keeps none unless told: see setFftWisdomFile in oefmt/registration/fft.h).
#pragma once

#include <string>

namespace oefmt {

/// The user's wisdom file: $OEFMT_FFTW_WISDOM if set ("" or "none": no file), else
/// $XDG_CACHE_HOME/oefmt/fftwf-wisdom-<host> (default cache: ~/.cache; host, as a home folder
/// may be shared between machines and wisdom describes one machine); "" when there is no home.
std::string defaultFftWisdomPath();

/// setFftWisdomFile(defaultFftWisdomPath()): what every program of the package does at start.
void useDefaultFftWisdom();

}  // namespace oefmt
