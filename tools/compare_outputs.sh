#!/usr/bin/env bash
# Proves that a change leaves netvmo's outputs unchanged: builds a reference commit and the
# working tree, runs both on the same inputs and compares every output file byte for byte.
#
#   bash tools/compare_outputs.sh [REF [NEW]] [--frames N] [--tolerance REL [--abs ABS]]
#
# REF defaults to the commit recorded in tools/compare_outputs.ref (the last commit before the
# restructuring); NEW to the working tree (uncommitted changes included). Compared:
#   simulate datasets/paper5.yaml and datasets/paper5_jacobian.yaml:
#       energies.csv, estimates.csv, orientation_x.csv, summary.json
#   render datasets/paper5_render.yaml: every image, calibration, network.yaml and truth file
#   run on that rendered dataset (each build on its own rendering):
#       estimates.csv, energies.csv, errors.csv, summary.json without its "timing" block
#   detect on that rendered dataset: detections.csv and the lines it prints (not the time per
#       image)
#   sweep on it (k_s 2,20): sweep.csv, inputs.csv
#   launch on it (lock-step, one process per camera over loopback DDS): estimates.csv,
#       energies.csv, errors.csv, summary.json without "timing", every node's node_<id>.csv
#   calibrate with a map (datasets/calib_map.yaml rendered, its map datasets/calib_map_tags.yaml)
#       and without (datasets/calib_moved.yaml rendered, 20 frames, --keep-going): every output
#       file (calibration.json without its wall times, "seconds") and the lines printed
#   render datasets/unsync.yaml (cameras on their own clocks) and run on it, on the union of
#       their image times: the rendering and the run's outputs as above; the same for
#       datasets/moving_cameras.yaml with cameras 2 and 3 put on their own clocks (25 frames/s
#       from 13 ms, 15 frames/s from 47 ms), 30 frames
#   (not the output folders' .lock files: they hold the writer's pid)
# Exit status 0 when everything is identical; a CSV file whose every field is the same number
# written differently (e.g. -0 and 0) counts as identical and is listed; otherwise the
# differing files are listed and the status is 1.
# --tolerance REL (numeric mode, for changes that move results by round-off): a text file that is
# not byte-identical passes when it has the same lines, the same text between the numbers, and
# every number within |a - b| <= max(REL * max(|a|, |b|), ABS) of the reference's (ABS default
# 1e-12); each such file is listed with the count and the largest absolute and relative (of
# numbers above ABS) differences of its numbers.
set -euo pipefail
cd "$(dirname "$0")/.."
top=$(pwd)

ref=""
new=""
frames=60
tolerance=""
abs_tol=1e-12
number='^[-+]?([0-9]+[.]?[0-9]*|[.][0-9]+)([eE][-+]?[0-9]+)?$'
while [ $# -gt 0 ]; do
  case "$1" in
    --frames) frames="$2"; shift 2 ;;
    --tolerance|--abs)
      [ $# -ge 2 ] && [[ "$2" =~ $number ]] || {
        echo "compare_outputs: $1 needs a number, got '${2:-}'" >&2
        exit 2
      }
      if [ "$1" = --tolerance ]; then tolerance="$2"; else abs_tol="$2"; fi
      shift 2 ;;
    -h|--help) awk 'NR > 1 && !/^#/ {exit} NR > 1 {sub(/^# ?/, ""); print}' "$0"; exit 0 ;;
    *) if [ -z "$ref" ]; then ref="$1"; else new="$1"; fi; shift ;;
  esac
done
[ -n "$ref" ] || ref=$(tr -d ' \n' < tools/compare_outputs.ref)
git rev-parse --verify -q "$ref^{commit}" >/dev/null || {
  echo "compare_outputs: '$ref' is not a commit of this repository (a shallow clone lacks it)" >&2
  exit 2
}

work=$(mktemp -d "${TMPDIR:-/tmp}/netvmo-compare.XXXXXX")
trap 'rm -rf "$work"' EXIT
mkdir -p "$work/ref-src"
git archive "$ref" | tar -x -C "$work/ref-src"
if [ -n "$new" ]; then
  git rev-parse --verify -q "$new^{commit}" >/dev/null || { echo "compare_outputs: '$new' is not a commit" >&2; exit 2; }
  mkdir -p "$work/new-src"
  git archive "$new" | tar -x -C "$work/new-src"
  new_src=$work/new-src new_build=$work/new-build
  new_name=$(git rev-parse --short "$new")
else
  new_src=$top new_build=$top/build-compare
  new_name="working tree $(git rev-parse --short HEAD)$(git diff --quiet HEAD || echo '+changes')"
fi
echo "compare_outputs: reference $(git rev-parse --short "$ref"), against $new_name, $frames frames"
launcher=()
if command -v ccache >/dev/null; then  # a compiler cache, where the machine has one
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
fi
build() {  # build SRC_DIR BUILD_DIR
  cmake -S "$1" -B "$2" -DNETVMO_BUILD_TESTS=OFF -DNETVMO_BUILD_BENCHMARKS=OFF "${launcher[@]}" >/dev/null
  cmake --build "$2" -j2 --target netvmo >/dev/null
}
echo "compare_outputs: building the reference"
build "$work/ref-src" "$work/ref-build"
echo "compare_outputs: building $new_name"
build "$new_src" "$new_build"

# The launches' DDS domain: one of this run's own (loopback only, as launch always is).
domain=$((100 + $$ % 100))
produce() {  # produce NETVMO NAME: outputs in $work/NAME, produced under one common path
  local bin=$1 out=$work/current
  mkdir -p "$out"
  for s in paper5 paper5_jacobian; do
    "$bin" simulate "$top/datasets/$s.yaml" --out "$out/sim_$s" --no-plots >/dev/null
  done
  "$bin" render "$top/datasets/paper5_render.yaml" --out "$out/dataset" --frames "$frames" --quiet >/dev/null
  "$bin" run "$out/dataset" --out "$out/run" --no-overlays --no-plots >/dev/null 2>&1
  # Every sub-step an exchange round through a transport (not the in-process fast path).
  "$bin" run "$out/dataset" --out "$out/run_lossy" --transport lossy --drop 0.3 --seed 7 \
    --no-overlays --no-plots >/dev/null 2>&1
  "$bin" run "$out/dataset" --out "$out/run_zero_offset" --estimator zero-offset \
    --no-overlays --no-plots >/dev/null 2>&1
  # detect's report too, all but its time per image
  "$bin" detect "$out/dataset" --out "$out/detect" --quiet | grep -v '^front end: .* ms per image' \
    >"$out/detect.txt"
  "$bin" sweep "$out/dataset" --out "$out/sweep" --ks 2,20 --no-plot >/dev/null 2>&1
  "$bin" launch "$out/dataset" --out "$out/launch" --domain "$domain" --no-overlays --no-plots \
    --timeout 300 >/dev/null 2>&1
  # calibrate, with a map of static tags and with a tag moved through the rig (each build on its
  # own renderings).
  "$bin" render "$top/datasets/calib_map.yaml" --out "$out/calib_map_dataset" --quiet >/dev/null
  "$bin" calibrate "$out/calib_map_dataset" --map "$top/datasets/calib_map_tags.yaml" \
    --out "$out/calibrate_map" --no-plots >"$out/calibrate_map.txt"
  "$bin" render "$top/datasets/calib_moved.yaml" --out "$out/calib_moved_dataset" --frames 20 \
    --quiet >/dev/null
  "$bin" calibrate "$out/calib_moved_dataset" --out "$out/calibrate_moved" --no-plots \
    --keep-going >"$out/calibrate_moved.txt" 2>/dev/null
  # Cameras on their own clocks: the run on the union of their image times.
  "$bin" render "$top/datasets/unsync.yaml" --out "$out/unsync_dataset" --quiet >/dev/null
  "$bin" run "$out/unsync_dataset" --out "$out/run_unsync" --no-overlays --no-plots >/dev/null 2>&1
  sed -e 's/^  - id: 2$/&\n    fps: 25\n    start: 0.013/' -e 's/^  - id: 3$/&\n    fps: 15\n    start: 0.047/' \
    "$top/datasets/moving_cameras.yaml" >"$work/moving_unsync.yaml"
  "$bin" render "$work/moving_unsync.yaml" --out "$out/moving_unsync_dataset" --frames 30 \
    --quiet >/dev/null
  "$bin" run "$out/moving_unsync_dataset" --out "$out/run_moving_unsync" --no-overlays \
    --no-plots >/dev/null 2>&1
  for c in calibrate_map calibrate_moved; do
    grep -v '"seconds":' "$out/$c/calibration.json" >"$out/$c/calibration.noseconds.json"
    rm "$out/$c/calibration.json"
  done
  # The nodes' logs, statistics and exchange timings hold wall-clock times; the DDS
  # configuration its own path.
  rm -f "$out"/launch/nodes/*.log "$out"/launch/nodes/*.json "$out/launch/cyclonedds.xml" \
    "$out/launch/messages.json" "$out/launch/exchange.json"
  # Wall-clock timings differ from run to run; everything else must not.
  for r in run run_lossy run_zero_offset launch run_unsync run_moving_unsync; do
    awk '/^  "timing": \{/ {skip = 1} !skip {print} skip && /^  \},?$/ {skip = 0}' \
      "$out/$r/summary.json" > "$out/$r/summary.notiming.json"
    rm "$out/$r/summary.json"
  done
  mv "$out" "$work/$2"
}
echo "compare_outputs: running the reference"
produce "$work/ref-build/netvmo" ref
echo "compare_outputs: running $new_name"
produce "$new_build/netvmo" new

# Two CSV files are numerically identical when they have the same lines and fields and every
# field is the same text or the same number (exact ==, so -0 and 0 agree, nothing else does).
same_numbers() {
  awk -F, 'NR == FNR { a[FNR] = $0; n = FNR; next }
           { if (!(FNR in a)) exit 1; split(a[FNR], x, ","); if (length(x) != NF) exit 1
             for (i = 1; i <= NF; i++)
               if (x[i] != $i && !(x[i] ~ /^-?[0-9.eE+-]+$/ && $i ~ /^-?[0-9.eE+-]+$/ && x[i] + 0 == $i + 0)) exit 1
             m = FNR }
           END { exit (m != n) }' "$1" "$2"
}
# Numeric mode: the same lines, the same text between the numbers, every number within the
# tolerance. Prints "COUNT MAX_ABS MAX_REL" of the differing numbers; status 1 when not within.
within_tolerance() {
  awk -v rel="$tolerance" -v abs="$abs_tol" '
    function split_numbers(s, num, txt,   k) {  # txt[0] num[1] txt[1] ... num[k] txt[k]
      k = 0
      while (match(s, /[-+]?([0-9]+[.]?[0-9]*|[.][0-9]+)([eE][-+]?[0-9]+)?/)) {
        txt[k] = substr(s, 1, RSTART - 1); num[++k] = substr(s, RSTART, RLENGTH)
        s = substr(s, RSTART + RLENGTH)
      }
      txt[k] = s
      return k
    }
    NR == FNR { a[FNR] = $0; n = FNR; next }
    {
      if (!(FNR in a)) { bad = 1; exit }
      ka = split_numbers(a[FNR], xa, ta); kb = split_numbers($0, xb, tb)
      if (ka != kb) { bad = 1; exit }
      for (i = 0; i <= ka; i++) if (ta[i] != tb[i]) { bad = 1; exit }
      for (i = 1; i <= ka; i++) {
        if (xa[i] == xb[i]) continue
        x = xa[i] + 0; y = xb[i] + 0; d = x - y; if (d < 0) d = -d
        if (d == 0) continue
        m = x < 0 ? -x : x; my = y < 0 ? -y : y; if (my > m) m = my
        count++
        if (d > max_abs) max_abs = d
        if (m > abs && d / m > max_rel) max_rel = d / m
        if (d > rel * m && d > abs) bad = 1
      }
      last = FNR
    }
    END {
      if (last != n) bad = 1
      printf "%d %.3g %.3g\n", count, max_abs, max_rel
      exit bad
    }' "$1" "$2"
}
status=0
count=0
numeric=0
rounded=0
while IFS= read -r f; do
  rel=${f#"$work/ref/"}
  count=$((count + 1))
  if ! cmp -s "$f" "$work/new/$rel"; then
    if [[ "$rel" == *.csv ]] && [ -f "$work/new/$rel" ] && same_numbers "$f" "$work/new/$rel"; then
      echo "numerically identical, not byte-identical: $rel"
      { diff "$f" "$work/new/$rel" || true; } | head -4 | sed "s/^/    /"
      numeric=$((numeric + 1))
    elif [ -n "$tolerance" ] && [ -f "$work/new/$rel" ] && grep -Iq . "$f" &&
         stats=$(within_tolerance "$f" "$work/new/$rel"); then
      read -r c a r <<< "$stats"
      echo "within tolerance: $rel ($c numbers differ, largest difference $a absolute, $r relative)"
      rounded=$((rounded + 1))
    else
      echo "DIFFERENT: $rel"
      status=1
    fi
  fi
done < <(find "$work/ref" -type f ! -name '*.lock' | sort)  # a lock notes its writer's pid
extra=$(cd "$work/new" && find . -type f ! -name '*.lock' | sort | sed 's|^\./||' | while read -r r; do [ -e "$work/ref/$r" ] || echo "$r"; done)
if [ -n "$extra" ]; then
  echo "only in $new_name: $extra"
  status=1
fi
if [ $status = 0 ] && [ $rounded != 0 ]; then
  echo "compare_outputs: all $count files identical or within tolerance $tolerance (absolute $abs_tol): $((count - rounded)) identical ($numeric of them numerically), $rounded within tolerance (listed above)"
elif [ $status = 0 ] && [ $numeric = 0 ]; then
  echo "compare_outputs: all $count files identical"
elif [ $status = 0 ]; then
  echo "compare_outputs: all $count files identical, $numeric of them numerically but not byte for byte (listed above)"
else
  echo "compare_outputs: outputs differ"
fi
exit $status
