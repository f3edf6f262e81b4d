#!/usr/bin/env bash
# Final error to g* of `netvmo launch --mode async` against injected loss and delay, on a rendered
# dataset, by default with the gains of the async test (k_e = 10, k_s = 100; KE=... KS=... to
# change them) at --speed 0.25 (a delay of D ms wall is D/4 ms of camera time). Writes OUT/sweep.dat (loss, delay_ms, worst camera's final
# position error [mm] and orientation error [deg], converged 1/0 against 1 cm / 1 deg) and draws
# OUT/sweep.png with gnuplot (pngcairo). Every launch is bounded (--timeout 60, and `timeout`);
# the Cyclone configuration is launch's own, loopback only. Not run by CI.
#
#   tools/async_sweep.sh BUILD_DIR OUT [FRAMES]   (FRAMES of datasets/paper5_render.yaml, 30)
set -euo pipefail
build=${1:?build folder}
out=${2:?output folder}
frames=${3:-30}
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
ke=${KE:-10}
ks=${KS:-100}
common=(--mode async --speed 0.25 --ke "$ke" --ks "$ks" --no-overlays --no-plots --timeout 60
        --stale "${STALE:-0.25}" --seed 7)
dat="$out/sweep.dat"
echo "# loss delay_ms position_mm orientation_deg converged" > "$dat"
timeout 120 "$build/netvmo" launch "$out/ds" --out "$out/lockstep" --ke "$ke" --ks "$ks" \
  --no-overlays --no-plots --timeout 60 > /dev/null
echo "# lock-step: $(worst "$out/lockstep/summary.json")" >> "$dat"
for loss in ${LOSSES:-0 0.1 0.3 0.5}; do
  for delay in ${DELAYS:-0 10 50 100}; do
    run="$out/run_${loss}_${delay}"
    if timeout 120 "$build/netvmo" launch "$out/ds" --out "$run" "${common[@]}" \
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
gnuplot <<GP
set terminal pngcairo size 900,420
set output "$out/sweep.png"
set multiplot layout 1,2
set xlabel "delay [ms, wall; camera time = delay / 4]"
set key top left
set ylabel "worst final position error to g* [mm]"
losses = "${LOSSES:-0 0.1 0.3 0.5}"
plot for [i=1:words(losses)] "$dat" index (i-1) using 2:3 with linespoints title sprintf("loss %s", word(losses, i))
set ylabel "worst final orientation error to g* [deg]"
plot for [i=1:words(losses)] "$dat" index (i-1) using 2:4 with linespoints notitle
unset multiplot
GP
echo "wrote $dat and $out/sweep.png"
