#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# Takes doc/rviz.png headless: renders a flight bag, replays it through the nodelet with rviz
# under Xvfb (software OpenGL) and grabs the screen near the end of the replay.
# Needs: rviz xvfb imagemagick (apt). Usage: scripts/rviz_screenshot.sh BUILD_DIR [OUTPUT.png]
set -eo pipefail
build="${1:?build directory}"
output="${2:-$(dirname "$0")/../doc/rviz.png}"
work="$(mktemp -d)"
trap 'kill $(jobs -p) 2>/dev/null || true; cp "$work/launch.log" /tmp/rviz_launch.log 2>/dev/null; rm -rf "$work"' EXIT
# shellcheck disable=SC1091
source "$build/devel/setup.bash"
export ROS_HOME="$work/ros" ROS_LOG_DIR="$work/ros/log" LIBGL_ALWAYS_SOFTWARE=1
"$build/devel/lib/oefmt/oefmt_simulate" --quiet --frames 120 --length 294.6 --bag "$work/flight.bag" "$work/flight"
Xvfb :87 -screen 0 1400x900x24 >/dev/null 2>&1 &
export DISPLAY=:87
sleep 2
altitude="$(awk '!/^#/ && NF >= 4 {print $4; exit}' "$work/flight/groundtruth.tum")"
roslaunch oefmt replay.launch bag:="$work/flight.bag" rate:=2 rviz:=true start_delay:=8 \
  initial_altitude:="$altitude" >"$work/launch.log" 2>&1 &
# 8 s start delay + 120 frames at 10 Hz (12 s): grab shortly before the end (the launch stops
# with the bag).
sleep 18
import -window root "$output"
echo "wrote $output"
