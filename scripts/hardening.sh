#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Hardening checks, separate from the main build. One clang++-14 build of fuzz/ (the
# core instrumented with AddressSanitizer + UBSan and libFuzzer's coverage) gives:
#   1. the unit tests under the sanitizers;
#   2. the libFuzzer targets, each run for SECONDS on a copy of its seeds;
# and 3. the ROS-free libraries (src/registration, estimation, io, evaluation) through the aarch64 compiler's front end (ARM companion
#    computers: the NEON paths; the AVX2 files are stubs there), warnings as errors.
# (The catkin build can also be sanitised with gcc: -DOEFMT_SANITIZE=ON.)
# Usage: bash scripts/hardening.sh BUILD_ROOT [SECONDS]   (SECONDS per fuzz target, default 20)
# Writes JUnit XML into OEFMT_RESULTS_DIR (default BUILD_ROOT/test_results/oefmt):
#   sanitizers-oefmt_unit_tests.xml (gtest), sanitizers-exit.xml (only when the run died or
#   leaked after gtest wrote its file), fuzz.xml (one case per fuzz target) and
#   portability.xml (one case per core source checked for aarch64).
# Exits non-zero on any failure. Builds are incremental when BUILD_ROOT is reused.
set -uo pipefail

if [ $# -lt 1 ]; then
  echo "usage: bash scripts/hardening.sh BUILD_ROOT [SECONDS]" >&2
  exit 2
fi
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
mkdir -p "$1"
root="$(cd "$1" && pwd)"
seconds="${2:-20}"
results="${OEFMT_RESULTS_DIR:-$root/test_results/oefmt}"
jobs="$(nproc)"
mkdir -p "$results"
failed=0
start=$SECONDS

section() { printf '\n==================== %s ====================\n' "$*"; }

# junit FILE SUITE [NAME STATUS LOG]...: one <testcase> per triple; STATUS "ok" or a failure
# message, LOG a file whose last lines go into the failure.
junit() {
  /usr/bin/python3 - "$@" <<'PYTHON'
import pathlib, sys, xml.etree.ElementTree as ET
path, suite, rest = sys.argv[1], sys.argv[2], sys.argv[3:]
cases = [rest[i:i + 3] for i in range(0, len(rest), 3)]
root = ET.Element("testsuite", name=suite, tests=str(len(cases)),
                  failures=str(sum(status != "ok" for _, status, _ in cases)), errors="0")
for name, status, log in cases:
    case = ET.SubElement(root, "testcase", classname=suite, name=name)
    if status != "ok":
        text = pathlib.Path(log).read_text(errors="replace") if pathlib.Path(log).is_file() else ""
        # XML 1.0 cannot hold most control characters (fuzzer logs may print input bytes).
        tail = "".join(c if c in "\n\t" or ord(c) >= 32 else "?" for c in text[-6000:])
        ET.SubElement(case, "failure", message=status).text = tail
ET.ElementTree(root).write(path, encoding="utf-8", xml_declaration=True)
PYTHON
}

# excerpt LOG: 40 lines from the first sanitizer, libFuzzer or contract report (else the end).
excerpt() {
  local first
  first="$(grep -n -m 1 -E 'ERROR: (AddressSanitizer|LeakSanitizer|libFuzzer)|runtime error:|CONTRACT VIOLATION|terminate called' "$1" | cut -d: -f1)"
  if [ -n "$first" ]; then sed -n "${first},$((first + 39))p" "$1"; else tail -n 40 "$1"; fi
}

# ---------------------------------------------------------------------------------------------
# 0. One sanitizer build for both checks
# ---------------------------------------------------------------------------------------------
fuzz="$root/fuzz"
fuzz_log="$fuzz/build.log"
targets=(fuzz_image fuzz_image_pair fuzz_cam_param fuzz_energy_vectors)
mkdir -p "$fuzz"
rm -f "$results/sanitizers-oefmt_unit_tests.xml" "$results/sanitizers-exit.xml"
section "Sanitizer build (clang++-14, ASan+UBSan): oefmt_unit_tests ${targets[*]} in $fuzz"
built=0
if cmake -S "$repo/fuzz" -B "$fuzz" -DCMAKE_CXX_COMPILER=clang++-14 >"$fuzz_log" 2>&1 &&
   cmake --build "$fuzz" -j"$jobs" >>"$fuzz_log" 2>&1; then
  built=1
else
  failed=1
  tail -n 40 "$fuzz_log"
  echo "FAILED: sanitizer build (log: $fuzz_log)"
fi
echo "(${SECONDS}s elapsed)"

# ---------------------------------------------------------------------------------------------
# 1. Unit tests under ASan + UBSan
# ---------------------------------------------------------------------------------------------
if [ $built = 1 ]; then
  section "ASan+UBSan: run oefmt_unit_tests"
  binary="$fuzz/oefmt_unit_tests"
  xml="$results/sanitizers-oefmt_unit_tests.xml"
  run_log="$fuzz/unit_tests.log"
  # In a subshell, so that the shell's own "Aborted" notice goes into the log too.
  (ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1 \
    "$binary" --gtest_output="xml:$xml"; exit $?) >"$run_log" 2>&1
  rc=$?
  grep -E '^\[  (PASSED|FAILED) +\]|tests ran' "$run_log" || true
  if [ $rc -ne 0 ]; then
    failed=1
    excerpt "$run_log"
    # gtest writes its XML only at a normal exit, and LeakSanitizer reports after it: record
    # the death (or leak) as a case of its own so the summary cannot miss it.
    junit "$results/sanitizers-exit.xml" Sanitizers oefmt_unit_tests "exit status $rc" "$run_log"
    echo "FAILED: oefmt_unit_tests under sanitizers (exit $rc; log: $run_log)"
  else
    echo "ok: oefmt_unit_tests under ASan+UBSan"
  fi
else
  junit "$results/sanitizers-exit.xml" Sanitizers build "sanitizer build failed" "$fuzz_log"
fi
echo "(${SECONDS}s elapsed)"

# ---------------------------------------------------------------------------------------------
# 2. libFuzzer targets
# ---------------------------------------------------------------------------------------------
cases=()
if [ $built = 1 ]; then
  section "Fuzz: ${seconds}s per target, up to $jobs at a time"
  # Fork mode: a timeout does not end the run; each one is replayed afterwards, and one that
  # hangs again fails (parameter files are read by yaml-cpp, no longer by OpenCV's YAML reader,
  # which looped forever on some documents kept in the corpus).
  # OPENCV_IO_MAX_IMAGE_PIXELS: OpenCV reads it at load time; it refuses images that claim
  # gigapixels, which would otherwise only measure the fuzzer's memory limit.
  fuzz_env=(OPENCV_IO_MAX_IMAGE_PIXELS=4194304 ASAN_OPTIONS=detect_leaks=1:abort_on_error=1
            UBSAN_OPTIONS=halt_on_error=1:print_stacktrace=1)
  run_target() {
    local target="$1" work="$fuzz/run/$1"
    rm -rf "$work"
    mkdir -p "$work/corpus" "$work/artifacts"
    cp "$repo/fuzz/corpus/$target/"* "$work/corpus/"
    env "${fuzz_env[@]}" "$fuzz/$target" -fork=1 -ignore_timeouts=1 -ignore_ooms=0 \
      -ignore_crashes=0 -max_total_time="$seconds" -rss_limit_mb=2048 -timeout=10 \
      -artifact_prefix="$work/artifacts/" "$work/corpus" >"$work/fuzz.log" 2>&1
    echo $? >"$work/status"
  }
  running=0
  for target in "${targets[@]}"; do
    run_target "$target" &
    running=$((running + 1))
    if [ $running -ge "$jobs" ]; then wait -n; running=$((running - 1)); fi
  done
  wait
  for target in "${targets[@]}"; do
    work="$fuzz/run/$target"
    rc="$(cat "$work/status" 2>/dev/null || echo 99)"
    runs="$(grep -o '^#[0-9]*' "$work/fuzz.log" | tail -n 1 | tr -d '#')"
    problem=""
    # 70: libFuzzer's timeout exit code, which fork mode passes on from its last job even
    # when timeouts are ignored; the timeouts are judged by their inputs below.
    [ "$rc" = 0 ] || [ "$rc" = 70 ] || problem="libFuzzer found a problem (exit $rc)"
    # Judge by the inputs libFuzzer saved, not only by its exit status (fork mode's first merge
    # of the seeds saves a crashing seed and carries on); each is replayed for its report.
    for input in "$work/artifacts"/*; do
      case "$input" in *.log | */\*) continue ;; esac
      env "${fuzz_env[@]}" "$fuzz/$target" -timeout=10 "$input" >"$input.log" 2>&1
      if [[ "$input" != */timeout-* ]]; then
        problem="libFuzzer saved $(basename "$input")"
        cat "$input.log" >>"$work/fuzz.log"
      elif grep -q 'ERROR: libFuzzer: timeout' "$input.log"; then
        problem="a hang: $input"
        cat "$input.log" >>"$work/fuzz.log"
      else
        echo "note: $target: $input timed out under load but not when replayed"
      fi
    done
    if [ -z "$problem" ]; then
      echo "ok: $target (${runs:-?} inputs)"
      cases+=("$target" ok "$work/fuzz.log")
    else
      failed=1
      echo "FAILED: $target: $problem (log: $work/fuzz.log; inputs: $work/artifacts/)"
      excerpt "$work/fuzz.log"
      cases+=("$target" "$problem; reproducer in $work/artifacts/" "$work/fuzz.log")
    fi
  done
else
  for target in "${targets[@]}"; do cases+=("$target" "sanitizer build failed" "$fuzz_log"); done
fi
junit "$results/fuzz.xml" Fuzz "${cases[@]}"

# ---------------------------------------------------------------------------------------------
# 3. The core on ARM: every file of the ROS-free libraries through the aarch64 compiler's front end (syntax and
#    semantics, front-end warnings; no code generation, which would double the time and could
#    not be linked anyway: Debian has no aarch64 OpenCV/Ceres here). OpenCV's and Eigen's
#    headers are the host's.
# ---------------------------------------------------------------------------------------------
section "Portability: the ROS-free libraries for aarch64 (g++ front end)"
arm="$root/aarch64"
mkdir -p "$arm"
cases=()
if command -v aarch64-linux-gnu-g++ >/dev/null; then
  compile_arm() {
    local source="$1" name
    name="$(basename "$source" .cpp)"
    aarch64-linux-gnu-g++ -std=c++17 -fsyntax-only -Wall -Wextra -Werror -fno-math-errno \
      -fopenmp-simd -I"$repo/include" -isystem /usr/include/opencv4 -isystem /usr/include/eigen3 \
      -idirafter /usr/include "$source" >"$arm/$name.log" 2>&1
    echo $? >"$arm/$name.status"
  }
  export -f compile_arm
  export repo arm
  core_sources=("$repo"/src/{registration,estimation,io,evaluation}/*.cpp)
  printf '%s\n' "${core_sources[@]}" | xargs -P "$jobs" -I{} bash -c 'compile_arm "$1"' _ {}
  compiled=0 sources=0
  for source in "${core_sources[@]}"; do
    name="$(basename "$source" .cpp)"
    sources=$((sources + 1))
    if [ "$(cat "$arm/$name.status" 2>/dev/null)" = 0 ]; then
      compiled=$((compiled + 1))
      cases+=("$name" ok "$arm/$name.log")
    else
      failed=1
      echo "FAILED: $name for aarch64 (log: $arm/$name.log)"
      head -n 20 "$arm/$name.log"
      cases+=("$name" "does not compile for aarch64" "$arm/$name.log")
    fi
  done
  echo "$compiled of $sources core sources pass the aarch64 compiler"
else
  failed=1
  echo "FAILED: aarch64-linux-gnu-g++ missing (apt install g++-aarch64-linux-gnu)"
  cases+=(aarch64-compiler "aarch64-linux-gnu-g++ missing" /dev/null)
fi
junit "$results/portability.xml" Portability "${cases[@]}"

section "Hardening: $([ $failed = 0 ] && echo passed || echo FAILED) in $((SECONDS - start))s (results: $results)"
exit $failed
