// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/simd_kernel.h"

namespace oefmt {

bool cpuRunsAvx2Kernels() {
  static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return has;
}

}  // namespace oefmt
