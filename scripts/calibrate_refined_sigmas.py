#!/usr/bin/env python3
# SPDX-License-Identifier: GPL-3.0-or-later
"""Calibrates the sigmas of the zoom refinement's readings, uncertainty.refined_rotation_scale and
uncertainty.refined_log_zoom_scale: renders flights that are not in the generalization corpus
(other seeds and scenes), runs oefmt_offline on each and compares both readings of every
registered pair's rotation, and every refined zoom, with the truth.

The pair's rotation is the inverse-variance mean of the rotation surface's reading (sigma: its
peak width times uncertainty.rotation_scale) and the zoom refinement's (sigma: its normal
equations' times uncertainty.refined_rotation_scale), see doc/method.md. Only their ratio sets
the weights, so the scale that puts both on the same footing is the one under which the same
share of errors (90 %) lies within the sigma for both:

  refined_rotation_scale = q90(|refined error| / refined sigma) / q90(|surface error| / surface sigma)

Where the refinement had not settled, the image blocks read the rotation (motion_blocks > 0), with
their sigma times a factor that puts it in refinement sigmas (kBlockSigmaInRefinementSigmas in
registration.cpp); the factor that gives the blocks' readings the same q90 as the refinement's is
printed beside the scale: the shipped factor times q90(blocks) / q90(refinement).

The refined zoom stands alone (the surface's peak width is about the same for every pair of a
scene and says nothing of it). Its sigma has two parts: the refinement's times the scale, and the
part of the slope correction that was not taken (sigma_slope_log_zoom, in ln zoom already and
not scaled). The scale is calibrated where it stands alone, on the zooms whose slope part is
zero, to put 90 % of their errors within 1.645 sigmas as for a normal distribution:

  refined_log_zoom_scale = q90(|refined zoom error| / refinement's zoom sigma) / 1.645

and the slope part is checked where it dominates (its q90 should be about 1.645 as well), as is
the share of all zooms within 1.645 of their combined sigma (about 90 %).

  scripts/calibrate_refined_sigmas.py [--tools build/devel/lib/oefmt] [--work build/calibration]
"""
import argparse
import csv
import math
import os
import sys

import benchmark_common as common

# Level circles with a fixed heading (the true rotation and zoom of every pair are zero and one,
# for every depth layer), 80 frames each,
# scenes unlike one another: the default one, natural texture, walls, weak texture, low overlap,
# brick.
FLIGHTS = [
    ("default", ["--seed", "41"]),
    ("natural", ["--seed", "42", "--texture-style", "natural"]),
    ("walls", ["--seed", "43", "--levels", "3,6", "--walls", "--altitude", "20"]),
    ("weak", ["--seed", "44", "--contrast", "12", "--noise-grey", "4", "--flicker", "0.08"]),
    ("overlap65", ["--seed", "45", "--overlap", "0.65", "--texture-style", "cells,noise,stripes"]),
    ("brick", ["--seed", "46", "--texture-style", "brick"]),
]
FRAMES = "80"
# kBlockSigmaInRefinementSigmas in src/registration/registration.cpp, as shipped.
BLOCK_SIGMA_FACTOR = 0.74
ROTATION_SCALE_KEY = "rotation_scale:"
# |x| of a normal distribution lies within this many sigmas 90 % of the time.
NORMAL_Q90 = 1.645
CALLER = "calibrate_refined_sigmas"


def quantile(values, q):
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, int(q * len(ordered)))]


def report_zoom_scale(zooms):
    """Prints refined_log_zoom_scale from the zooms (error, refinement's sigma, slope sigma) whose
    slope part is zero, and checks the slope part and the combined sigma on the others."""
    alone = [error / refined for error, refined, slope in zooms if slope == 0.0]
    if not alone:
        print("zoom       no refined zoom without a slope part")
        return
    scale = quantile(alone, 0.9) / NORMAL_Q90
    print(f"zoom       {len(alone):3d} refined zooms without a slope part: 90 % of errors within "
          f"{quantile(alone, 0.9):.2f} refinement sigmas -> refined_log_zoom_scale {scale:.1f}")
    sloped = [error / slope for error, refined, slope in zooms if slope > scale * refined]
    if sloped:
        print(f"slope      {len(sloped):3d} zooms whose slope part is the larger: 90 % of errors within "
              f"{quantile(sloped, 0.9):.2f} slope sigmas ({NORMAL_Q90} for a calibrated sigma)")
    within = sum(1 for error, refined, slope in zooms if error <= NORMAL_Q90 * math.hypot(scale * refined, slope))
    print(f"combined   {len(zooms):3d} refined zooms: {100.0 * within / len(zooms):.0f} % of errors within "
          f"{NORMAL_Q90} combined sigmas (90 % for a calibrated sigma)")


def rotation_scale(tools):
    """uncertainty.rotation_scale as shipped (oefmt_parameters --yaml)."""
    for line in common.run([os.path.join(tools, "oefmt_parameters"), "--yaml"], CALLER).splitlines():
        if line.strip().startswith(ROTATION_SCALE_KEY):
            return float(line.split(":")[1])
    sys.exit("uncertainty.rotation_scale not found in oefmt_parameters --yaml")


def ratios(tools, work, name, options, surface_scale):
    folder = common.render(tools, os.path.join(work, name), ["--frames", FRAMES, *options], CALLER)
    diagnostics = os.path.join(work, name + ".csv")
    common.run([os.path.join(tools, "oefmt_offline"), "--quiet", "--images", folder, "--mode", "oefmt",
                "--output", os.path.join(work, name + ".tum"), "--diagnostics", diagnostics], CALLER)
    surface, refined, blocks, zooms = [], [], [], []
    with open(diagnostics, newline="") as table:
        for row in csv.DictReader(table):
            sigma_zoom = float(row["sigma_refined_log_zoom"])
            if row["state"] == "tracking" and sigma_zoom > 0.0:
                zooms.append((abs(math.log(float(row["zoom"]))), sigma_zoom, float(row["sigma_slope_log_zoom"])))
            sigma_refined = float(row["sigma_refined_theta_rad"])
            if row["state"] != "tracking" or not sigma_refined > 0.0:
                continue
            # A fixed heading: the true rotation of every pair is zero.
            surface.append(abs(float(row["theta_rad"])) / (surface_scale * float(row["sigma_theta_rad"])))
            ratio = abs(float(row["refined_theta_rad"])) / sigma_refined
            (blocks if int(row["motion_blocks"]) > 0 else refined).append(ratio)
    return surface, refined, blocks, zooms


def main():
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    here = os.path.dirname(os.path.abspath(__file__))
    parser.add_argument("--tools", default=os.path.join(here, "..", "build", "devel", "lib", "oefmt"))
    parser.add_argument("--work", default=os.path.join(here, "..", "build", "calibration"))
    args = parser.parse_args()
    os.makedirs(args.work, exist_ok=True)
    surface_scale = rotation_scale(args.tools)
    all_surface, all_refined, all_blocks, all_zooms = [], [], [], []
    for name, options in FLIGHTS:
        surface, refined, blocks, zooms = ratios(args.tools, args.work, name, options, surface_scale)
        all_zooms += zooms
        if not refined:
            print(f"{name:10s} no refined pair")
            continue
        blocks_q90 = f"{quantile(blocks, 0.9):.2f}" if blocks else "-"
        print(f"{name:10s} {len(surface):3d} pairs: 90 % of errors within {quantile(surface, 0.9):.2f} surface "
              f"sigmas, {quantile(refined, 0.9):.2f} refinement sigmas; {len(blocks)} read by blocks: "
              f"{blocks_q90}; {len(zooms)} refined zooms: "
              f"{quantile([e / r for e, r, _ in zooms], 0.9) if zooms else 0:.2f}")
        all_surface += surface
        all_refined += refined
        all_blocks += blocks
    if not all_refined:
        sys.exit("no refined pair in any flight")
    q_surface, q_refined = quantile(all_surface, 0.9), quantile(all_refined, 0.9)
    print(f"all        {len(all_surface):3d} pairs: {q_surface:.2f} surface sigmas, {q_refined:.2f} refinement "
          f"sigmas -> refined_rotation_scale {q_refined / q_surface:.1f}")
    if all_blocks:
        q_blocks = quantile(all_blocks, 0.9)
        print(f"blocks     {len(all_blocks):3d} pairs: {q_blocks:.2f} sigmas -> the blocks' sigma factor "
              f"{BLOCK_SIGMA_FACTOR * q_blocks / q_refined:.2f} (shipped {BLOCK_SIGMA_FACTOR})")
    if all_zooms:
        report_zoom_scale(all_zooms)


if __name__ == "__main__":
    main()
