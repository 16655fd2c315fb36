#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Tilt benchmark: flights of a multirotor without gimbal (leaning into its acceleration, with a
wobble of 8 deg at 1 Hz), each beside its level twin (the same flight, the same scene, flown
level). Renders them with oefmt_simulate (with an IMU and a downward rangefinder), runs
oefmt_offline in oefmt mode with and without them, and prints one row per flight:

  level        ATE of the level twin (similarity alignment in x-y)
  IMU + range  ATE, and the metric trajectory's scale error: |scale - 1| of the similarity
               alignment, the path length's error (no alignment: the estimate's 3-D path over
               the truth's, on the frames both have) and the ATE of a rigid alignment (no scale)
  IMU only     ATE with the IMU and without the rangefinder (--no-range), and its ratio to level;
               the same with an exact IMU attitude (a second render whose imu.txt has no
               attitude error: what the levelling itself costs)
  neither      ATE with neither (--no-imu --no-range): tilt read as translation

  scripts/tilt_benchmark.py [--markdown] [--flights a,b]
"""
import argparse
import json
import math
import os

import benchmark_common as common

HERE = os.path.dirname(os.path.abspath(__file__))
TILT = ["--tilt", "--wobble", "8", "--wobble-hz", "1", "--imu", "--range"]
FLIGHTS = [
    ("circle", "circle", []),
    ("circle-climb", "circle climbing 8 m and back", ["--climb", "8", "--seed", "31"]),
    ("eight", "figure-8, 880 m", ["--track", "eight", "--seed", "32"]),
    ("line-climb", "line climbing 5 m, heading on the track", ["--track", "line", "--climb", "5",
                                                                "--heading", "track", "--seed", "33"]),
    ("line-parallax", "line, tops at 40 % of 20 m, walls (the plane below changes)",
     ["--track", "line", "--altitude", "20", "--levels", "8", "--walls", "--heading", "track",
      "--direction", "30", "--seed", "34"]),
]


def run(command):
    return common.run(command, "tilt_benchmark")


def render(tools, folder, options):
    common.render(tools, folder, options, "tilt_benchmark")


def offline(tools, folder, output, *flags):
    run([os.path.join(tools, "oefmt_offline"), "--quiet", "--images", folder, "--output", output, *flags])
    return output


def evaluate(tools, trajectory, truth, rigid=False):
    return common.evaluate(tools, trajectory, truth, "tilt_benchmark", rigid=rigid)


def positions_by_stamp(path):
    return {round(row[0], 3): tuple(row[1:4]) for row in common.read_tum(path)}


def path_length_error(trajectory, truth):
    """|L_estimate / L_truth - 1| of the 3-D paths over the frames both have (matched by stamp)."""
    estimate, reference = positions_by_stamp(trajectory), positions_by_stamp(truth)
    stamps = sorted(set(estimate) & set(reference))
    def length(poses):
        return sum(math.dist(poses[a], poses[b]) for a, b in zip(stamps, stamps[1:]))
    return abs(length(estimate) / length(reference) - 1.0)


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--tools", default=os.path.join(HERE, "..", "build", "devel", "lib", "oefmt"))
    parser.add_argument("--work", default=os.path.join(HERE, "..", "build", "tilt"))
    parser.add_argument("--flights", help="comma-separated names (default: all)")
    parser.add_argument("--markdown", action="store_true", help="a markdown table (doc/results.md)")
    args = parser.parse_args()
    chosen = args.flights.split(",") if args.flights else [f[0] for f in FLIGHTS]
    rows = []
    for name, what, options in FLIGHTS:
        if name not in chosen:
            continue
        level, tilted = os.path.join(args.work, name + "-level"), os.path.join(args.work, name + "-tilted")
        render(args.tools, level, options)
        render(args.tools, tilted, options + TILT)
        exact = os.path.join(args.work, name + "-tilted-exact")
        render(args.tools, exact, options + TILT + ["--attitude-error", "0"])
        truth_level, truth = os.path.join(level, "groundtruth.tum"), os.path.join(tilted, "groundtruth.tum")
        level_ate = evaluate(args.tools, offline(args.tools, level, os.path.join(level, "oefmt.tum")),
                             truth_level)["ate"]["rmse"]
        full = offline(args.tools, tilted, os.path.join(tilted, "imu-range.tum"))
        full_sim, full_rigid = evaluate(args.tools, full, truth), evaluate(args.tools, full, truth, rigid=True)
        imu = evaluate(args.tools, offline(args.tools, tilted, os.path.join(tilted, "imu.tum"), "--no-range"), truth)
        imu_exact = evaluate(args.tools, offline(args.tools, exact, os.path.join(exact, "imu.tum"), "--no-range"),
                             os.path.join(exact, "groundtruth.tum"))
        neither = evaluate(args.tools, offline(args.tools, tilted, os.path.join(tilted, "neither.tum"),
                                               "--no-imu", "--no-range"), truth)
        rows.append({"name": name, "what": what, "level": level_ate, "full": full_sim["ate"]["rmse"],
                     "scale_error": abs(full_sim["scale"] - 1.0), "path_error": path_length_error(full, truth),
                     "rigid": full_rigid["ate"]["rmse"],
                     "imu": imu["ate"]["rmse"], "heading_max": imu["heading_steps"]["max_deg"],
                     "imu_exact": imu_exact["ate"]["rmse"],
                     "neither": neither["ate"]["rmse"]})
    header = ["flight", "level ATE [m]", "IMU + range: ATE [m]", "scale error [%]", "path length error [%]",
              "rigid ATE [m]",
              "IMU only: ATE [m]", "ratio to level", "max heading step error [deg]",
              "exact attitude: ATE [m]", "ratio to level", "neither: ATE [m]"]
    lines = []
    for r in rows:
        lines.append([f"{r['name']} ({r['what']})", f"{r['level']:.2f}", f"{r['full']:.2f}",
                      f"{100 * r['scale_error']:.2f}", f"{100 * r['path_error']:.2f}", f"{r['rigid']:.2f}",
                      f"{r['imu']:.2f}",
                      f"{r['imu'] / r['level']:.1f}", f"{r['heading_max']:.2f}", f"{r['imu_exact']:.2f}",
                      f"{r['imu_exact'] / r['level']:.1f}", f"{r['neither']:.1f}"])
    if args.markdown:
        print("| " + " | ".join(header) + " |")
        print("|" + "---|" * len(header))
        for line in lines:
            print("| " + " | ".join(line) + " |")
    else:
        for line in lines:
            print("  ".join(f"{h}: {v}" for h, v in zip(header, line)))
    print(json.dumps(rows))


if __name__ == "__main__":
    main()
