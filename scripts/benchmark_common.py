# SPDX-License-Identifier: GPL-3.0-or-later
"""What the benchmark scripts share: running the package's tools, rendering a flight once per set
of options, reading TUM trajectories and evaluating one against its ground truth."""

import hashlib
import json
import os
import shutil
import subprocess
import sys


def run(command, caller):
    """Runs a tool; stops the calling script (named `caller`) with the tool's message on failure."""
    result = subprocess.run(command, capture_output=True, text=True)
    if result.returncode != 0:
        sys.exit(f"{caller}: {' '.join(command)} failed (exit status {result.returncode}):\n"
                 f"{result.stderr.strip()}")
    return result.stdout


def render(tools, folder, options, caller):
    """Renders a flight with oefmt_simulate into `folder` unless a render with the same options is
    there (a stale one is removed first)."""
    key = hashlib.sha256(json.dumps(options).encode()).hexdigest()
    stamp = os.path.join(folder, ".options")
    if os.path.exists(stamp) and open(stamp).read() == key:
        return folder
    shutil.rmtree(folder, ignore_errors=True)
    run([os.path.join(tools, "oefmt_simulate"), "--quiet", *options, folder], caller)
    with open(stamp, "w") as out:
        out.write(key)
    return folder


def read_tum(path):
    """The rows of a TUM file (t x y z qx qy qz qw), comments left out."""
    rows = []
    with open(path) as tum:
        for line in tum:
            if line.strip() and not line.startswith("#"):
                rows.append([float(v) for v in line.split()])
    return rows


def evaluate(tools, trajectory, truth, caller, rigid=False, match="time"):
    """oefmt_evaluate's figures (its JSON line) of `trajectory` against `truth`."""
    command = [os.path.join(tools, "oefmt_evaluate"), "--json-only", "--match", match, trajectory, truth]
    if rigid:
        command.append("--no-scale")
    return json.loads(run(command, caller).strip().splitlines()[-1])
