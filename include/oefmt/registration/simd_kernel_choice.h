// SPDX-License-Identifier: GPL-3.0-or-later
// Which code runs the per-pixel and per-frequency loops that have a CPU-specific version.
#pragma once

namespace oefmt {

/// kAuto runs the AVX2 + FMA kernels when the CPU has both (the same results up to float
/// rounding), kPortable the code every CPU runs (SSE on x86-64-v2, NEON on ARM; for
/// comparisons and benchmarks). Off x86-64 both are the portable code.
enum class SimdKernel { kAuto, kPortable };

/// True when kAuto picks the AVX2 + FMA kernels on this CPU.
bool cpuRunsAvx2Kernels();

}  // namespace oefmt
