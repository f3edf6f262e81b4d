#!/usr/bin/env bash
# Final error to g* of `netvmo launch --mode async` against injected loss and delay, on a rendered
# dataset, by default with the default gains (k_e = 1, k_s = 50; KE=... KS=... to change them) at
# --speed 0.25 (a delay of D ms wall is D/4 ms of camera time). Writes OUT/sweep.dat (loss,
# delay_ms, worst camera's final position error [mm] and orientation error [deg], converged 1/0
# against 1 cm / 1 deg), OUT/decay.dat (worst position error per frame without loss, one block per
# delay, with the predicted decay rate, docs/processes.md, "Loss and delay in async mode") and draws OUT/sweep.png with
# gnuplot (pngcairo). LOSSES="..." and DELAYS="..." change the grid. Every launch is bounded
# (--timeout 120, and `timeout`); the Cyclone configuration is launch's own, loopback only. Not run
# by CI.
#
#   tools/async_sweep.sh BUILD_DIR OUT [FRAMES]   (FRAMES of datasets/paper5_render.yaml, 150)
set -euo pipefail
build=${1:?build folder}
out=${2:?output folder}
frames=${3:-150}
here=$(cd "$(dirname "$0")/.." && pwd)
mkdir -p "$out"
if [ ! -f "$out/ds/network.yaml" ]; then
  timeout 300 "$build/netvmo" render "$here/datasets/paper5_render.yaml" --frames "$frames" \
    --out "$out/ds" > /dev/null
fi
worst() {  # summary.json -> "position_mm orientation_deg"
  python3 - "$1" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
p = max(c["networked"]["vs_g_star"]["final_position_m"] for c in s["cameras"])
r = max(c["networked"]["vs_g_star"]["final_orientation_deg"] for c in s["cameras"])
print(f"{1000 * p:.2f} {r:.3f}")
PY
}
ke=${KE:-1}
ks=${KS:-50}
common=(--mode async --speed 0.25 --ke "$ke" --ks "$ks" --no-overlays --no-plots --timeout 120
        --stale "${STALE:-0.25}" --seed 7)
dat="$out/sweep.dat"
echo "# loss delay_ms position_mm orientation_deg converged" > "$dat"
timeout 180 "$build/netvmo" launch "$out/ds" --out "$out/lockstep" --ke "$ke" --ks "$ks" \
  --no-overlays --no-plots --timeout 120 > /dev/null
echo "# lock-step: $(worst "$out/lockstep/summary.json")" >> "$dat"
for loss in ${LOSSES:-0 0.1 0.3 0.5}; do
  for delay in ${DELAYS:-0 10 50 100}; do
    run="$out/run_${loss}_${delay}"
    if timeout 180 "$build/netvmo" launch "$out/ds" --out "$run" "${common[@]}" \
      --drop "$loss" --delay "$delay" > "$run.log" 2>&1; then
      read -r p r <<< "$(worst "$run/summary.json")"
      ok=$(python3 -c "print(int($p < 10 and $r < 1))")
      echo "$loss $delay $p $r $ok" >> "$dat"
    else
      echo "$loss $delay nan nan 0" >> "$dat"
    fi
  done
  printf "\n\n" >> "$dat"
done
cat "$dat"
# Worst camera's position error over camera time without loss, per delay, and the predicted decay
# rate of the slow (average) mode, k_e |V| / (n + 2 k_s |E| tau) (docs/processes.md, "Loss and delay in async mode"), with
# |V| the cameras' mean number seeing the target (lock-step summary), tau = delay / 4 (camera time).
python3 - "$out" "$ke" "$ks" ${DELAYS:-0 10 50 100} > "$out/decay.dat" <<'PY'
import csv, json, math, sys
out, ke, ks, delays = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), sys.argv[4:]
net = open(f"{out}/ds/network.yaml").read()
n = len(json.load(open(f"{out}/lockstep/summary.json"))["cameras"])
edges = sum(1 for l in net.split("edges:")[1].splitlines() if l.strip().startswith("- ["))
seen = sum(c["seen_fraction"] for c in json.load(open(f"{out}/lockstep/summary.json"))["cameras"])
print(f"# n {n} |E| {edges} |V| {seen:.2f} k_e {ke:g} k_s {ks:g}")
for d in delays:
    tau = float(d) / 4000.0
    rate = ke * seen / (n + 2 * ks * edges * tau)
    print(f"# delay {d} ms wall: tau {1000 * tau:g} ms, predicted rate {rate:.3f} /s")
    try:
        rows = list(csv.DictReader(open(f"{out}/run_0_{d}/errors.csv")))
    except OSError:
        rows = []
    pts = []
    for r in rows:
        w = [float(r[k]) for k in r if k.endswith("position_mm") and r[k] not in ("", "nan")]
        if w:
            pts.append((float(r["t"]), max(w)))
    anchor = min(pts, key=lambda q: abs(q[0] - 2.0)) if pts else None
    for t, w in pts:
        pred = anchor[1] * math.exp(-rate * (t - anchor[0])) if t >= anchor[0] else float("nan")
        print(f"{t:.4f} {w:.3f} {pred:.3f}")
    print("\n")
PY
grep '^#' "$out/decay.dat"
gnuplot <<GP
set terminal pngcairo size 1350,420
set output "$out/sweep.png"
set multiplot layout 1,3
set key top left
delays = "${DELAYS:-0 10 50 100}"
set xlabel "camera time [s]"
set ylabel "worst position error to g* [mm], loss 0"
set logscale y
set title "dashed: predicted decay rate k_e|V| / (n + 2 k_s|E|tau) from t = 2 s" font ",10"
plot for [i=1:words(delays)] "$out/decay.dat" index (i-1) using 1:2 with lines lw 2 lc i \
       title sprintf("delay %s ms wall", word(delays, i)), \
     for [i=1:words(delays)] "$out/decay.dat" index (i-1) using 1:3 with lines lc i dt 2 notitle
unset logscale y
unset title
set xlabel "delay [ms, wall; camera time = delay / 4]"
set ylabel "worst final position error to g* [mm]"
losses = "${LOSSES:-0 0.1 0.3 0.5}"
plot for [i=1:words(losses)] "$dat" index (i-1) using 2:3 with linespoints title sprintf("loss %s", word(losses, i))
set ylabel "worst final orientation error to g* [deg]"
plot for [i=1:words(losses)] "$dat" index (i-1) using 2:4 with linespoints notitle
unset multiplot
GP
echo "wrote $dat, $out/decay.dat and $out/sweep.png"
