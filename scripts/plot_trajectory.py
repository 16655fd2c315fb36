#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Plots an aligned estimate against the ground truth: top view and error over time.

Input: the CSV that oefmt_evaluate writes (t, truth_x/y/z, estimate_x/y/z, error), one row per
matched pose. Usage: plot_trajectory.py DATA.csv OUT.png [--title TEXT]
"""
import argparse
import csv
import sys

import matplotlib

matplotlib.use("Agg")  # no display needed
import matplotlib.pyplot as plt  # noqa: E402


def read_rows(path):
    with open(path, newline="") as handle:
        rows = list(csv.DictReader(handle))
    if not rows:
        raise ValueError(f"{path}: no poses")
    return {key: [float(row[key]) for row in rows] for key in rows[0]}


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("data", help="CSV written by oefmt_evaluate")
    parser.add_argument("output", help="PNG to write")
    parser.add_argument("--title", default="")
    args = parser.parse_args()
    try:
        d = read_rows(args.data)
    except (OSError, ValueError, KeyError) as error:
        print(f"plot_trajectory.py: {error}", file=sys.stderr)
        return 1

    figure, (top, error) = plt.subplots(1, 2, figsize=(13, 5.5), gridspec_kw={"width_ratios": [1.2, 1]})
    top.plot(d["truth_x"], d["truth_y"], "-", color="0.3", linewidth=2, label="ground truth")
    top.plot(d["estimate_x"], d["estimate_y"], "-", color="tab:red", linewidth=1.2, label="estimate (aligned)")
    top.plot(d["truth_x"][0], d["truth_y"][0], "o", color="tab:green", label="start")
    top.set_xlabel("x (east) [m]")
    top.set_ylabel("y (north) [m]")
    top.set_aspect("equal", adjustable="datalim")
    top.grid(True, alpha=0.3)
    top.legend(loc="best")
    top.set_title("top view")

    error.plot(d["t"], d["error"], color="tab:red", linewidth=1.2)
    error.set_xlabel("time [s]")
    error.set_ylabel("absolute position error [m]")
    error.grid(True, alpha=0.3)
    rmse = (sum(e * e for e in d["error"]) / len(d["error"])) ** 0.5
    error.set_title(f"error over time (rmse {rmse:.3f} m, max {max(d['error']):.3f} m)")

    if args.title:
        figure.suptitle(args.title)
    figure.tight_layout()
    figure.savefig(args.output, dpi=110)
    return 0


if __name__ == "__main__":
    sys.exit(main())
