// SPDX-License-Identifier: GPL-3.0-or-later
#include "oefmt/registration/simd_kernel_choice.h"

namespace oefmt {

bool cpuRunsAvx2Kernels() {
#if defined(__x86_64__)
  static const bool has = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
  return has;
#else
  return false;  // ARM (Jetson, Raspberry Pi) and others: the portable NEON / scalar code
#endif
}

}  // namespace oefmt
