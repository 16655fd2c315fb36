#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Whole-run speed of oefmt_offline: wall time per frame, CPU time and peak memory of each run,
and how much of the CPUs' time the hypervisor took meanwhile (`steal` in /proc/stat).

On a shared virtual machine the wall time of the same run varies by a factor of two from one
minute to the next, and steal is the part of that the guest can see. Every run is printed; the
summary gives the median over all runs and over the runs in which the hypervisor took less than
--max-steal of the CPUs' time.

  scripts/measure_speed.py --runs 10 --images ../shared/datasets/circle --no-undistort
"""
import argparse
import os
import statistics
import subprocess
import sys
import tempfile

# Runs in a child of its own, so that RUSAGE_CHILDREN holds exactly one oefmt_offline run.
TIMED_RUN = """
import resource, subprocess, sys, time
start = time.perf_counter()
status = subprocess.run(sys.argv[1:]).returncode
if status != 0:
    sys.exit(status)
wall = time.perf_counter() - start
usage = resource.getrusage(resource.RUSAGE_CHILDREN)
print(wall, usage.ru_utime + usage.ru_stime, usage.ru_maxrss)
"""


def cpu_ticks():
    """(steal, all) jiffies of all CPUs since boot, or None without /proc/stat."""
    try:
        with open("/proc/stat") as stat:
            fields = [int(v) for v in stat.readline().split()[1:9]]
    except (OSError, ValueError):
        return None
    # user nice system idle iowait irq softirq steal (guest time is already in user)
    return (fields[7] if len(fields) == 8 else 0), sum(fields)


def frame_count(trajectory_path):
    with open(trajectory_path) as trajectory:
        return sum(1 for line in trajectory if line.strip() and not line.startswith("#"))


def timed_run(command):
    """wall s, CPU s, peak resident kB of one run, and the hypervisor's share meanwhile."""
    before = cpu_ticks()
    result = subprocess.run([sys.executable, "-c", TIMED_RUN] + command, capture_output=True,
                            text=True)
    after = cpu_ticks()
    if result.returncode != 0:
        sys.exit(f"measure_speed: oefmt_offline failed (exit status {result.returncode}):\n"
                 f"{result.stderr.strip()}")
    wall, cpu, peak_kb = result.stdout.split()[-3:]
    steal = None
    if before and after and after[1] > before[1]:
        steal = (after[0] - before[0]) / (after[1] - before[1])
    return float(wall), float(cpu), int(peak_kb), steal


def main():
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--images", required=True, help="dataset folder, as oefmt_offline takes it")
    parser.add_argument("--offline", help="oefmt_offline executable (default: this checkout's "
                                          "build/devel/lib/oefmt/oefmt_offline)")
    parser.add_argument("--runs", type=int, default=10, help="number of runs (default 10)")
    parser.add_argument("--max-steal", type=float, default=0.02,
                        help="largest share of the CPUs' time the hypervisor may take in a run "
                             "that counts as undisturbed (default 0.02)")
    args, extra = parser.parse_known_args()
    offline = args.offline or os.path.join(os.path.dirname(os.path.abspath(__file__)), os.pardir,
                                           "build", "devel", "lib", "oefmt", "oefmt_offline")
    if not os.access(offline, os.X_OK):
        sys.exit(f"measure_speed: no executable oefmt_offline at {offline} (build first, or "
                 "give --offline)")
    if args.runs < 1:
        sys.exit("measure_speed: --runs must be at least 1")

    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        output = os.path.join(tmp, "trajectory.tum")
        command = [offline, "--quiet", "--images", args.images, "--output", output] + extra
        for i in range(args.runs):
            wall, cpu, peak_kb, steal = timed_run(command)
            frames = frame_count(output)
            if frames == 0:
                sys.exit("measure_speed: the run wrote no pose")
            rows.append((1e3 * wall / frames, cpu, peak_kb, steal))
            steal_text = "unknown" if steal is None else f"{100 * steal:.1f} %"
            print(f"run {i + 1}: {wall:.3f} s, {1e3 * wall / frames:.2f} ms per frame ({frames} "
                  f"frames), CPU {cpu:.2f} s, peak memory {peak_kb / 1024:.1f} MB, steal "
                  f"{steal_text}", flush=True)

    def summary(label, selected):
        if not selected:
            print(f"{label}: none")
            return
        per_frame = sorted(r[0] for r in selected)
        print(f"{label}: {len(selected)} runs, median {statistics.median(per_frame):.2f} ms per "
              f"frame (fastest {per_frame[0]:.2f}, slowest {per_frame[-1]:.2f}), mean CPU "
              f"{statistics.mean(r[1] for r in selected):.2f} s, peak memory up to "
              f"{max(r[2] for r in selected) / 1024:.1f} MB")

    summary("all runs", rows)
    summary(f"runs with steal below {100 * args.max_steal:g} %",
            [r for r in rows if r[3] is not None and r[3] < args.max_steal])


if __name__ == "__main__":
    main()
