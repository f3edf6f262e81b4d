#!/usr/bin/env bash
# netvmo launch at scale: for each N, a rendered rig of N cameras (320x240, on a circle around a
# tagged target, those in front seeing it; a 3-regular graph: ring neighbours and the opposite
# camera, as bench_scale's), run as N `netvmo node` processes in lock-step, front ends included,
# and printed as one table row: time to discovery (the slowest node), estimates each node takes
# per round (its degree: it reads its neighbours' topics only), the round time (publish and
# receive, the median of the nodes' medians; the largest p99; a frame's first round apart, since
# it also waits for the neighbours' front ends) and the launch's wall time, next to `netvmo run`
# of the same dataset in one process (the anchor, measured in the same run), and whether the
# launch's estimates.csv is byte for byte the run's.
#
#   bash tools/scale_launch.sh [--frames F] [--build DIR] [--keep DIR] [--check] N...
#                                                                          (default: 16 32 64)
# --check (a test): exit 1 unless every launch equals its run and every node takes exactly its
# 3 neighbours' estimates per round.
#
# Loopback only (launch's configuration); each launch is bounded by launch's --timeout.
set -euo pipefail
cd "$(dirname "$0")/.."
frames=6
build=build
keep=""
check=0
sizes=()
while [ $# -gt 0 ]; do
  case "$1" in
    --frames) frames="$2"; shift 2 ;;
    --build) build="$2"; shift 2 ;;
    --keep) keep="$2"; shift 2 ;;
    --check) check=1; shift ;;
    -h|--help) sed -n '2,16p' "$0"; exit 0 ;;
    *) sizes+=("$1"); shift ;;
  esac
done
[ ${#sizes[@]} -gt 0 ] || sizes=(16 32 64)
netvmo="$build/netvmo"
[ -x "$netvmo" ] || { echo "scale_launch: $netvmo not built (cmake --build $build --target netvmo)" >&2; exit 1; }
work=${keep:-$(mktemp -d)}
mkdir -p "$work"
[ -n "$keep" ] || trap 'rm -rf "$work"' EXIT

# The scenario of N cameras (N even, >= 4).
scenario() {
  local n=$1
  cat <<YAML
# $n cameras on a circle of radius 2.2 m around a tagged target (tools/scale_launch.sh).
fps: 30
frames: $frames
imaging: {spp: 1, seed: 1, exposure: 1.0, ambient: 0.3, background: 0.6, noise: false}
lights:
  - {type: directional, direction: [0.45, 0.6, -1.0], intensity: 0.8, shadows: false}
target:
  tag: {family: tag36h11, id: 0, size: 0.3, quiet_cells: 1}
  shapes:
    - {type: box, size: [0.4, 0.4, 0.4], pose: {p: [0, 0, -0.201]},
       material: {pattern: noise, albedo: 0.62, albedo2: 0.12, scale: 0.05, seed: 11}}
  motion: {type: static, pose: {p: [0.0, 0.0, 1.1], r: [1.5707963, 0, 0]}}
cameras:
YAML
  awk -v n="$n" 'BEGIN {
    pi = atan2(0, -1);
    for (k = 0; k < n; ++k) {
      a = 2 * pi * k / n;
      x = 2.2 * sin(a); y = -2.2 * cos(a);
      printf "  - id: %d\n", k + 1;
      printf "    intrinsics: {width: 320, height: 240, fx: 300, fy: 300, cx: 159.5, cy: 119.5}\n";
      printf "    pose: {eye: [%.4f, %.4f, 1.6], look_at: [0.0, 0.0, 1.1], up: [0, 0, 1]}\n", x, y;
      printf "    believed_offset: {dp: [%.3f, %.3f, 0.01], dr: [0.01, %.3f, 0.02]}\n",
             0.02 * cos(3 * a), 0.02 * sin(5 * a), 0.02 * cos(7 * a);
    }
    printf "edges: [";
    for (k = 0; k < n; ++k) {
      printf "%s[%d, %d]", (k ? ", " : ""), k + 1, (k + 1) % n + 1;
      if (k < n / 2) printf ", [%d, %d]", k + 1, k + n / 2 + 1;
    }
    printf "]\n";
  }'
  cat <<YAML
occluders:
  - name: floor
    shapes:
      - {type: plane, size: [12, 12], pose: {p: [0, 0, 0]},
         material: {pattern: checker, albedo: 0.55, albedo2: 0.32, scale: 0.5}}
YAML
}

printf '%-5s %-12s %-12s %-16s %-14s %-16s %-10s %-8s %s\n' n discovery_s taken/round \
  round_median_us round_p99_us first_round_us launch_s run_s "launch = run"
failed=0
for n in "${sizes[@]}"; do
  if [ $((n % 2)) -ne 0 ] || [ "$n" -lt 4 ]; then echo "scale_launch: N must be even and >= 4 ($n)" >&2; exit 1; fi
  d="$work/n$n"
  rm -rf "$d"; mkdir -p "$d"
  scenario "$n" > "$d/scenario.yaml"
  "$netvmo" render "$d/scenario.yaml" --out "$d/ds" > "$d/render.log" 2>&1
  t0=$(date +%s.%N)
  "$netvmo" run "$d/ds" --out "$d/run" --no-overlays --no-plots > "$d/run.log" 2>&1
  t1=$(date +%s.%N)
  "$netvmo" launch "$d/ds" --out "$d/launch" --no-overlays --no-plots --timeout 500 \
    --node-timeout 120 > "$d/launch.log" 2>&1 || { echo "scale_launch: launch of $n failed, see $d/launch.log" >&2; tail -3 "$d/launch.log" >&2; exit 1; }
  t2=$(date +%s.%N)
  line=$(grep '^exchange:' "$d/launch.log")
  # exchange: N nodes, discovery D s (slowest), round M us (...), p99 P us (largest), T estimates ...
  disc=$(sed -E 's/.*discovery ([0-9.]+) s.*/\1/' <<<"$line")
  med=$(sed -E 's/.*, round ([0-9.]+) us \(median.*/\1/' <<<"$line")
  p99=$(sed -E 's/.*p99 ([0-9.]+) us.*/\1/' <<<"$line")
  first=$(sed -E 's/.*first round ([0-9.]+) us.*/\1/' <<<"$line")
  taken=$(sed -E 's/.*, ([0-9.]+) estimates taken per round.*/\1/' <<<"$line")
  same=no
  if cmp -s "$d/run/estimates.csv" "$d/launch/estimates.csv"; then same=yes; fi
  [ "$same" = yes ] && [ "$taken" = "3.00" ] || failed=1
  printf '%-5s %-12s %-12s %-16s %-14s %-16s %-10.1f %-8.1f %s\n' "$n" "$disc" "$taken" "$med" \
    "$p99" "$first" "$(awk -v a="$t1" -v b="$t2" 'BEGIN{print b-a}')" \
    "$(awk -v a="$t0" -v b="$t1" 'BEGIN{print b-a}')" "$same"
done
echo "($(date -u +%Y-%m-%d), $(nproc) cores, $(grep -m1 'model name' /proc/cpuinfo | sed 's/.*: //'); $frames frames)"
if [ "$check" = 1 ] && [ "$failed" = 1 ]; then
  echo "scale_launch: a launch differs from its run or a node took other than its 3 neighbours' estimates per round" >&2
  exit 1
fi
