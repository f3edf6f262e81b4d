#!/usr/bin/env bash
# netvmo calibrate's accuracy against the truth over noise seeds (docs/calibration.md,
# "Measured"): renders a scenario once per seed, calibrates it and prints per camera the mean and
# max pose error, the predicted standard deviation (sqrt of the covariance's trace), how often
# the truth lies inside the 99 % ellipsoid (d^2 <= 16.81, 6 dof), the naive per-frame OpenCV
# solvePnP average on the same detections (map case), and the time per camera-frame.
#
#   tools/calib_accuracy.sh [OUT]      (default OUT: /tmp/netvmo_calib_accuracy)
# Environment: NETVMO (default build/netvmo), SEEDS (default 1..10), FRAMES (default: the
# scenario's), SCENARIO (default datasets/calib_map.yaml), MAP (default
# datasets/calib_map_tags.yaml; empty: the moved-tag case, e.g. SCENARIO=datasets/calib_moved.yaml
# MAP=), CLEAN=1 (clean imaging: camera_model realistic replaced by clean).
set -euo pipefail
netvmo=${NETVMO:-build/netvmo}
out=${1:-/tmp/netvmo_calib_accuracy}
seeds=${SEEDS:-1 2 3 4 5 6 7 8 9 10}
scenario=${SCENARIO:-datasets/calib_map.yaml}
map=${MAP-datasets/calib_map_tags.yaml}
mkdir -p "$out"
if [ "${CLEAN:-0}" = 1 ]; then
  sed 's/camera_model: realistic/camera_model: clean/' "$scenario" > "$out/scenario.yaml"
  scenario=$out/scenario.yaml
fi
frames_opt=()
[ -n "${FRAMES:-}" ] && frames_opt=(--frames "$FRAMES")
map_opt=()
[ -n "$map" ] && map_opt=(--map "$map")
for s in $seeds; do
  "$netvmo" render "$scenario" --out "$out/ds_$s" --seed "$s" "${frames_opt[@]}" > /dev/null 2>&1
  "$netvmo" calibrate "$out/ds_$s" "${map_opt[@]}" --out "$out/cal_$s" --no-plots --keep-going \
    > "$out/cal_$s.log"
done
python3 - "$out" $seeds <<'PY'
import json, math, sys
out, seeds = sys.argv[1], sys.argv[2:]
rows = {}
for s in seeds:
    j = json.load(open(f"{out}/cal_{s}/calibration.json"))
    for c in j["cameras"]:
        if not c["ok"] or "vs_truth" not in c or c.get("reference"):
            continue
        r = rows.setdefault(c["id"], {"p": [], "o": [], "sp": [], "so": [], "d2": [], "naive": [],
                                      "naive_o": [], "t": []})
        v = c["vs_truth"]
        r["p"].append(v["position_mm"]); r["o"].append(v["orientation_deg"])
        cov = c["covariance"]
        r["sp"].append(1e3 * math.sqrt(sum(cov[k][k] for k in range(3))))
        r["so"].append(math.degrees(math.sqrt(sum(cov[k][k] for k in range(3, 6)))))
        r["d2"].append(v.get("d2", float("nan")))
        if "naive_pnp" in c and "vs_truth" in c["naive_pnp"]:
            r["naive"].append(c["naive_pnp"]["vs_truth"]["position_mm"])
            r["naive_o"].append(c["naive_pnp"]["vs_truth"]["orientation_deg"])
        r["t"].append(1e3 * c["seconds"] / max(1, c["images"]))
mean = lambda v: sum(v) / len(v) if v else float("nan")
print(f"{len(seeds)} seeds")
print("| camera | position error mean / max [mm] | predicted sd [mm] | orientation error mean / max [deg] | predicted sd [deg] | truth in 99 % ellipsoid | naive solvePnP average: position mean / max [mm], orientation mean [deg] | ms per camera-frame |")
print("|---|---|---|---|---|---|---|---|")
total_in = total = 0
for cid in sorted(rows):
    r = rows[cid]
    inside = sum(1 for d in r["d2"] if d <= 16.81)
    total_in += inside; total += len(r["d2"])
    naive = (f"{mean(r['naive']):.1f} / {max(r['naive']):.1f}, {mean(r['naive_o']):.2f}"
             if r["naive"] else "-")
    print(f"| {cid} | {mean(r['p']):.1f} / {max(r['p']):.1f} | {mean(r['sp']):.1f} | "
          f"{mean(r['o']):.3f} / {max(r['o']):.3f} | {mean(r['so']):.3f} | {inside} of {len(r['d2'])} | "
          f"{naive} | {mean(r['t']):.1f} |")
print(f"coverage: {total_in} of {total} camera-runs inside the 99 % ellipsoid")
PY
