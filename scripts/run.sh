#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# One entry point for newcomers and CI:
#   bash scripts/run.sh demo   install dependencies, build, run the demo
#   bash scripts/run.sh test   install dependencies, build, run every test (unit + rostest)
#   bash scripts/run.sh build  install dependencies and build only
# Environment: OEFMT_BUILD_DIR (default: build), OEFMT_SKIP_INSTALL=1 to skip apt.
set -eo pipefail

repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${OEFMT_BUILD_DIR:-$repo/build}"
command="${1:-demo}"

# Debian 12 packages (ROS 1 is packaged by Debian; no other source is used).
packages=(
  build-essential cmake pkg-config catkin ros-base-dev libroscpp-dev libnodelet-dev
  libcv-bridge-dev libimage-geometry-dev libimage-transport-dev libtf2-ros-dev libtf2-msgs-dev libtf2-geometry-msgs-dev librosbag-dev
  ros-nav-msgs ros-sensor-msgs ros-geometry-msgs ros-message-generation ros-message-runtime
  libdiagnostic-updater-dev libceres-dev libopencv-dev libeigen3-dev libfftw3-dev libspng-dev libdeflate-dev
  libcli11-dev zlib1g-dev libyaml-cpp-dev
  libgtest-dev libbenchmark-dev librostest-dev python3-rostest python3-roslaunch python3-rosbag
  rosbash python3-std-msgs python3-sensor-msgs python3-nav-msgs python3-geometry-msgs
  python3-tf2-ros python3-diagnostic-msgs python3-numpy python3-matplotlib
)
# The test command also builds the sanitizer, fuzzing and ARM checks (scripts/hardening.sh).
test_packages=(clang-14 libclang-rt-14-dev g++-aarch64-linux-gnu)

install_dependencies() {
  [ "${OEFMT_SKIP_INSTALL:-0}" = 1 ] && return 0
  local missing=() wanted=("${packages[@]}")
  [ "$command" = test ] && wanted+=("${test_packages[@]}")
  for p in "${wanted[@]}"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  echo "== installing ${#missing[@]} Debian packages: ${missing[*]}"
  local sudo=""
  [ "$(id -u)" -ne 0 ] && sudo="sudo"
  $sudo apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $sudo apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

configure() {
  # Absolute interpreter paths: a pyenv/venv python3 first on PATH lacks catkin_pkg.
  cmake -S "$repo" -B "$build" -DCMAKE_BUILD_TYPE=Release \
    -DPYTHON_EXECUTABLE=/usr/bin/python3 -DPython3_EXECUTABLE=/usr/bin/python3 >/dev/null
}

build_all() {
  configure
  cmake --build "$build" -j"$(nproc)"
  # catkin caches its test environment at configure time: configure again now that the
  # generated Python messages exist, so Python test nodes can import them.
  configure
}

ros_environment() {
  # setup.bash reads unset variables: source it before any `set -u`.
  # shellcheck disable=SC1091
  source "$build/devel/setup.bash"
  export ROS_HOME="$build/ros_home" ROS_LOG_DIR="$build/ros_home/log"
  mkdir -p "$ROS_LOG_DIR"
}

run_tests() {
  cmake --build "$build" --target tests -j"$(nproc)"
  ros_environment
  rm -rf "$build/test_results"
  cmake --build "$build" --target run_tests -j1 || true  # always exits 0; judged below
  # Unit tests under ASan+UBSan and every libFuzzer target for 20 s (one separate clang build
  # in $build/hardening); their JUnit files join the others, so the summary judges them too.
  OEFMT_RESULTS_DIR="$build/test_results/oefmt" bash "$repo/scripts/hardening.sh" "$build/hardening" 20 || true
  # The generalization benchmark's small subset of generated flights, all three modes, its
  # requirements as JUnit cases (the whole corpus: scripts/generalization_benchmark.py).
  /usr/bin/python3 "$repo/scripts/generalization_benchmark.py" --subset ci --tools "$build/devel/lib/oefmt" \
    --work "$build/generalization" --junit "$build/test_results/oefmt/generalization.xml" || true
  # Show catkin's own view of failures, then count cases (catkin double-counts gtest cases).
  catkin_test_results "$build/test_results" 2>&1 | grep -E -v "^(Skipping|Summary)" || true
  /usr/bin/python3 "$repo/scripts/test_summary.py" "$build/test_results"
}

run_demo() {
  ros_environment
  bash "$repo/scripts/demo.sh" "$build" "$build/demo"
}

case "$command" in
  build) install_dependencies; build_all ;;
  test) install_dependencies; build_all; run_tests ;;
  demo) install_dependencies; build_all; run_demo ;;
  *) echo "usage: bash scripts/run.sh [demo|test|build]" >&2; exit 2 ;;
esac
