#!/usr/bin/env bash
# SPDX-License-Identifier: GPL-3.0-or-later
# The demo: render the simulator's default multi-depth circle flight, run the odometry on it in
# oefmt and fmt modes, evaluate both against the ground truth, print the errors side by side and
# plot the oefmt trajectory. Usage: scripts/demo.sh BUILD_DIR [OUTPUT_DIR] [extra oefmt_simulate
# options, e.g. --track eight]
set -eo pipefail
build="${1:?build directory}"
out="${2:-$build/demo}"
shift 2 || true
bin="$build/devel/lib/oefmt"
mkdir -p "$out"

echo "== rendering the flight into $out/flight"
"$bin/oefmt_simulate" "$@" "$out/flight"
# Altitude of the first frame above the ground (groundtruth z): metric output.
altitude="$(awk '!/^#/ && NF >= 4 {print $4; exit}' "$out/flight/groundtruth.tum")"

for mode in oefmt fmt; do
  echo "== oefmt_offline --mode $mode"
  "$bin/oefmt_offline" --images "$out/flight" --mode "$mode" --altitude "$altitude" \
    --output "$out/$mode.tum" --diagnostics "$out/$mode.csv"
  plot_args=()
  [ "$mode" = oefmt ] && plot_args=(--plot "$out/trajectory.png" --title "oefmt on the simulated circle")
  "$bin/oefmt_evaluate" --match index "${plot_args[@]}" --json-only \
    "$out/$mode.tum" "$out/flight/groundtruth.tum" > "$out/$mode.json"
done

/usr/bin/python3 - "$out" <<'PY'
import json, sys
out = sys.argv[1]
rows = [("ATE mean [m]", lambda r: r["ate"]["mean"]), ("ATE median [m]", lambda r: r["ate"]["median"]),
        ("ATE rmse [m]", lambda r: r["ate"]["rmse"]), ("ATE max [m]", lambda r: r["ate"]["max"]),
        ("drift [% of distance]", lambda r: r["drift_percent"]),
        ("loop error [m]", lambda r: r["loop_error"]), ("path length [m]", lambda r: r["path_length"])]
results = {}
for mode in ("oefmt", "fmt"):
    with open(f"{out}/{mode}.json") as f:
        results[mode] = json.loads(f.read().strip().splitlines()[-1])
print(f"\n{'similarity-aligned error':28s}{'oefmt':>12s}{'fmt':>12s}")
for name, get in rows:
    print(f"{name:28s}{get(results['oefmt']):12.3f}{get(results['fmt']):12.3f}")
print(f"\ntrajectories: {out}/oefmt.tum {out}/fmt.tum  plot: {out}/trajectory.png")
PY
