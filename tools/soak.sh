#!/usr/bin/env bash
# Soak (not a CI test): the pipeline over many network frames, recording resident memory and
# time per frame as it goes, then a plot.
#
#   tools/soak.sh BUILD_DIR OUT [FRAMES [SOURCE]]   run (default 100000 frames, recorded) and plot
#   tools/soak.sh --plot OUT                        redraw OUT/soak.png from OUT/soak.dat (partial
#                                                   tables too)
#
# SOURCE recorded: a 60-frame render of datasets/paper5_render.yaml (5 cameras, 640x480) played in
# a loop: PNG decoding + AprilTag front end + PnP + in-process networked observer (11 rounds per
# frame), ~12 ms per network frame on a quiet machine. SOURCE live: the static scene rendered every
# frame at 1 spp (radiance reused, new sensor noise), ~27 ms per frame. Every 1,000 frames
# `netvmo bench --soak` appends "frames seconds ms_per_frame vmrss_kb" to OUT/soak.dat (flushed).
# Run it niced in the background, e.g.
#   nice -n 19 tools/soak.sh build results/soak > results/soak.log 2>&1 &
set -euo pipefail
here=$(cd "$(dirname "$0")/.." && pwd)

plot() {
  local out=$1
  gnuplot <<GP
set terminal pngcairo size 900,420 enhanced font 'Sans,10'
set output '$out/soak.png.partial'
set multiplot layout 1,2 title 'soak: $(head -1 "$out/soak.dat" | sed 's/^# netvmo bench --soak: //; s/'"'"'//g')' noenhanced font 'Sans,9'
set grid
set xlabel 'network frames [thousands]'
set ylabel 'resident memory VmRSS [MB]'
set yrange [0:*]
plot '$out/soak.dat' using (\$1/1000):(\$4/1024) with linespoints pt 7 ps 0.4 lw 2 notitle
set ylabel 'time per network frame [ms] (mean of each 1,000)'
plot '$out/soak.dat' using (\$1/1000):3 with linespoints pt 7 ps 0.4 lw 2 lc rgb '#d62728' notitle
unset multiplot
GP
  mv "$out/soak.png.partial" "$out/soak.png"
  echo "plot: $out/soak.png"
}

if [[ ${1:-} == --plot ]]; then
  plot "${2:?usage: tools/soak.sh --plot OUT}"
  exit 0
fi
build=$(realpath "${1:?usage: tools/soak.sh BUILD_DIR OUT [FRAMES [SOURCE]]}")
out=${2:?usage: tools/soak.sh BUILD_DIR OUT [FRAMES [SOURCE]]}
frames=${3:-100000}
source=${4:-recorded}
mkdir -p "$out"
out=$(realpath "$out")
cd "$here"  # the scenario's name in the table and the plot stays relative
"$build/netvmo" bench --scenario datasets/paper5_render.yaml --frames 60 \
  --soak "$frames" --soak-every 1000 --soak-source "$source" --soak-log "$out/soak.dat"
plot "$out"
