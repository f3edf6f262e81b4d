#!/usr/bin/env bash
# The figures of docs/realistic_camera.md: per effect, a 200 x 150 rendering of a tag 1.3 m from
# the camera, clean (left) and with the effect strong enough to see (right), written to
# docs/figures/realistic_<effect>.png. Needs netvmo (build/netvmo or --netvmo PATH) and
# ImageMagick's convert. EFFECT names: only those figures (default: all).
#
#   bash tools/realistic_figures.sh [--netvmo PATH] [EFFECT ...]
set -euo pipefail
cd "$(dirname "$0")/.."
netvmo=build/netvmo
if [ "${1:-}" = "--netvmo" ]; then netvmo=$2; shift 2; fi
only=("$@")
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT

# $1 print, $2 sensor, $3 target velocity [m/s], $4 imaging extras, $5 light direction,
# $6 intrinsics (default: 200 x 150, fx = fy = 600)
scene() {
  cat <<YAML
fps: 30
frames: 1
imaging: {spp: 16, seed: 2, ambient: 0.3, background: 0.45, noise: false$4}
lights:
  - {type: directional, direction: $5, intensity: 0.7, shadows: true}
target:
  tag: {family: tag36h11, id: 7, size: 0.16, print: $1}
  shapes:
    - {type: box, size: [0.24, 0.24, 0.05], pose: {p: [0, 0, -0.026]},
       material: {pattern: noise, albedo: 0.5, albedo2: 0.1, scale: 0.04, seed: 1}}
  motion: {type: twist, pose: {p: [0, 0, 1.3], r: [3.05, 0, 0.25]}, v: [$3, 0, 0]}
cameras:
  - {id: 1, intrinsics: {${6:-width: 200, height: 150, fx: 600, fy: 600}}, sensor: $2,
     pose: {p: [0, 0, 0], r: [0, 0, 0]}}
YAML
}

render() {  # $1 name, then scene's arguments; prints the PNG of the one image
  scene "$2" "$3" "$4" "$5" "$6" "$7" > "$tmp/$1.yaml"
  "$netvmo" render "$tmp/$1.yaml" --out "$tmp/$1" > "$tmp/$1.log" 2>&1 || { cat "$tmp/$1.log" >&2; exit 1; }
  local img
  img=$(ls "$tmp/$1"/cam_1/000000.* | head -1)
  convert "$img" "$tmp/$1.png"
  echo "$tmp/$1.png"
}

figure() {  # $1 effect, $2 print, $3 sensor, [$4 velocity, $5 imaging extras, $6 light,
            #  $7 intrinsics of the effect's camera]
  local v=${4:-0} extra=${5:-} light=${6:-"[0.3, 0.4, 1.0]"} lens=${7:-}
  local a b
  if [ ${#only[@]} -gt 0 ] && [[ " ${only[*]} " != *" $1 "* ]]; then return; fi
  a=$(render "clean_$1" clean clean "$v" "$extra" "$light" "")
  b=$(render "$1" "$2" "$3" "$v" "$extra" "$light" "$lens")
  convert "$a" "$b" -background white -splice 4x0 +append -chop 4x0 \
    -strip -define png:compression-level=9 "docs/figures/realistic_$1.png"
  echo "docs/figures/realistic_$1.png $(stat -c %s "docs/figures/realistic_$1.png") bytes"
}

mkdir -p docs/figures
figure ink_spread "{ink_spread: 0.3}" clean
figure ink_shrink "{ink_spread: -0.3}" clean
figure border_side "{border_width: [1, 1.4, 1, 0.6]}" clean
figure bent "{bend: -8}" clean
figure gloss "{gloss: 0.6, shininess: 8}" clean 0 "" "[0, 0, 1]"
figure srgb clean "{tone: srgb}"
figure bloom clean "{full_well: 200, bloom: 0.5}" 0 ", exposure: 1.5"
figure vignetting clean "{vignetting: poly, vignetting_poly: [-0.7, 0, 0]}"
figure psf clean "{psf_sigma: 1.5}"
figure jpeg clean "{jpeg_quality: 15}"
figure sharpen clean "{psf_sigma: 1.0, sharpen_amount: 2.0, sharpen_sigma: 1.5}"
figure motion_blur clean "{exposure_time: 0.02}" 1.0
figure rolling_shutter clean "{line_delay: 1.0e-4}" 2.0
figure defocus clean "{f_number: 1.4, focal_length_mm: 25, focus_distance: 3.0}"
figure fisheye clean clean 0 "" "[0.3, 0.4, 1.0]" \
  "width: 200, height: 150, fx: 260, fy: 260, lens: fisheye, distortion: [0.2, 0.1, 0, 0]"
figure realistic realistic realistic 0.5 ", noise: true"
