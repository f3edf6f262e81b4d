#!/usr/bin/env bash
# What each effect of the realistic camera model (docs/realistic_camera.md) does to the current
# front end: renders one small scene per effect (the same geometry each time: three static
# cameras at about 1.1, 1.9 and 4.5 m from a 0.16 m tag36h11 that moves at 0.5 m/s and turns
# slowly), runs `netvmo detect` on it and prints one Markdown table row per effect: fully
# visible tags accepted (netvmo detect's recall against truth.csv), the front end's rejection
# reasons, and the RMS / max corner error of accepted corners against the projected truth.
#
#   bash tools/realistic_effects.sh [--netvmo PATH] [--frames N] [--out DIR]
#                                   [--spp N] [--sampling grid|jittered] [EFFECT ...]
#
# EFFECT names (default: all): clean ink+0.2 ink-0.2 side0.95 side1.05 side0.85 side1.15 bent1
# bent gloss srgb vignetting psf1.0 bloom jpeg50 sharpen blur20ms rolling30us defocus realistic
# (side0.95, side0.85: the border that many cells wide on the bottom side; side1.05, side1.15:
# on the right side; bent1, bent: the card bent to a radius of 1 m and 0.25 m, its ends curling
# toward the camera). --spp, --sampling: imaging.spp and imaging.sampling of the scenes (default
# 9, grid). Takes about a minute per effect on two shared cores at the default 20 frames.
set -euo pipefail
cd "$(dirname "$0")/.."
netvmo=build/netvmo
frames=20
out=""
sampling=grid
spp=9
effects=()
while [ $# -gt 0 ]; do
  case "$1" in
    --netvmo) netvmo=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --sampling) sampling=$2; shift 2 ;;
    --spp) spp=$2; shift 2 ;;
    -h|--help) sed -n '2,17p' "$0"; exit 0 ;;
    *) effects+=("$1"); shift ;;
  esac
done
[ ${#effects[@]} -gt 0 ] || effects=(clean ink+0.2 ink-0.2 side0.95 side1.05 side0.85 side1.15 bent1 bent gloss srgb vignetting psf1.0 bloom
                                     jpeg50 sharpen blur20ms rolling30us defocus realistic)
[ -x "$netvmo" ] || { echo "realistic_effects.sh: no netvmo at $netvmo (build it, or --netvmo PATH)" >&2; exit 1; }
if [ -z "$out" ]; then out=$(mktemp -d); trap 'rm -rf "$out"' EXIT; fi
mkdir -p "$out"

# Per effect: the tag's print: map and every camera's sensor: map.
effect_keys() {
  case "$1" in
    clean) echo "clean|clean" ;;
    ink+0.2) echo "{ink_spread: 0.2}|clean" ;;
    ink-0.2) echo "{ink_spread: -0.2}|clean" ;;
    side0.95) echo "{border_width: [1, 1, 0.95, 1]}|clean" ;;
    side1.05) echo "{border_width: [1, 1.05, 1, 1]}|clean" ;;
    side0.85) echo "{border_width: [1, 1, 0.85, 1]}|clean" ;;
    side1.15) echo "{border_width: [1, 1.15, 1, 1]}|clean" ;;
    bent1) echo "{bend: -1}|clean" ;;
    bent) echo "{bend: -4}|clean" ;;
    gloss) echo "{gloss: 0.3, shininess: 20}|clean" ;;
    srgb) echo "clean|{tone: srgb}" ;;
    vignetting) echo "clean|{vignetting: cos4}" ;;
    psf1.0) echo "clean|{psf_sigma: 1.0}" ;;
    bloom) echo "clean|{full_well: 120, bloom: 0.5}" ;;
    jpeg50) echo "clean|{jpeg_quality: 50}" ;;
    sharpen) echo "clean|{psf_sigma: 0.8, sharpen_amount: 1.5, sharpen_sigma: 1.0}" ;;
    blur20ms) echo "clean|{exposure_time: 0.02}" ;;
    rolling30us) echo "clean|{line_delay: 3.0e-5}" ;;
    defocus) echo "clean|{f_number: 1.4, focal_length_mm: 8, focus_distance: 1.0}" ;;
    realistic) echo "realistic|realistic" ;;
    *) echo "realistic_effects.sh: unknown effect '$1'" >&2; exit 1 ;;
  esac
}

scenario() {  # $1 print, $2 sensor
  cat <<YAML
fps: 30
frames: $frames
imaging: {spp: $spp, seed: 3, ambient: 0.3, background: 0.6, noise: true, sampling: $sampling}
lights:
  - {type: directional, direction: [0.3, 0.8, -1.0], intensity: 0.8, shadows: true}
target:
  tag: {family: tag36h11, id: 5, size: 0.16, print: $1}
  shapes:
    - {type: box, size: [0.24, 0.24, 0.1], pose: {p: [0, 0, -0.051]},
       material: {pattern: noise, albedo: 0.6, albedo2: 0.12, scale: 0.05, seed: 2}}
  motion: {type: twist, pose: {p: [-0.15, 0.0, 1.1], r: [1.5707963, 0, 0]}, v: [0.5, 0, 0], w: [0, 0.3, 0]}
cameras:
  - {id: 1, intrinsics: {width: 640, height: 480, fx: 600, fy: 600}, sensor: $2,
     pose: {eye: [0.2, -1.1, 1.3], look_at: [0.0, 0.0, 1.1], up: [0, 0, 1]}}
  - {id: 2, intrinsics: {width: 640, height: 480, fx: 600, fy: 600}, sensor: $2,
     pose: {eye: [-0.8, -1.7, 1.2], look_at: [0.0, 0.0, 1.1], up: [0, 0, 1]}}
  - {id: 3, intrinsics: {width: 640, height: 480, fx: 600, fy: 600}, sensor: $2,
     pose: {eye: [0.6, -4.4, 1.6], look_at: [0.0, 0.0, 1.1], up: [0, 0, 1]}}
edges: [[1, 2], [2, 3]]
occluders:
  - name: room
    shapes:
      - {type: plane, size: [10, 10], material: {pattern: checker, albedo: 0.55, albedo2: 0.32, scale: 0.5}}
      - {type: box, size: [10, 0.2, 4], pose: {p: [0, 2.0, 2.0]},
         material: {pattern: noise, albedo: 0.5, albedo2: 0.25, scale: 0.3, seed: 3}}
YAML
}

echo "| effect | print / sensor | fully visible tags accepted | rejections (status: count) | accepted corners RMS / max error [px] |"
echo "|---|---|---|---|---|"
for e in "${effects[@]}"; do
  keys=$(effect_keys "$e")
  print=${keys%%|*}
  sensor=${keys#*|}
  dir="$out/$e"
  mkdir -p "$dir"
  scenario "$print" "$sensor" > "$dir/scenario.yaml"
  "$netvmo" render "$dir/scenario.yaml" --out "$dir/dataset" > "$dir/render.log" 2>&1
  "$netvmo" detect "$dir/dataset" --out "$dir/detect" > "$dir/detect.log" 2>&1
  python3 - "$e" "$print" "$sensor" "$dir" <<'PY'
import csv, math, re, sys
effect, print_, sensor, d = sys.argv[1:5]
log = open(f"{d}/detect.log").read()
m = re.search(r"fully visible tags detected.*?:((?: \S+ \d+/\d+)+)", log)
det = vis = 0
for a, b in re.findall(r"(\d+)/(\d+)", m.group(1) if m else ""):
    det += int(a); vis += int(b)
truth = {(r["frame"], r["camera"]): r for r in csv.DictReader(open(f"{d}/dataset/truth.csv"))}
reasons, errs = {}, []
for r in csv.DictReader(open(f"{d}/detect/detections.csv")):
    t = truth.get((r["frame"], r["camera"]))
    full = t and t["in_fov"] == "1" and float(t["visible_fraction"]) >= 0.999
    if r["detected"] == "1":
        if t and t["u0"]:
            for k in range(4):
                errs.append(math.hypot(float(r[f"u{k}"]) - float(t[f"u{k}"]),
                                       float(r[f"v{k}"]) - float(t[f"v{k}"])))
    elif full:
        reasons[r["status"]] = reasons.get(r["status"], 0) + 1
rms = math.sqrt(sum(e * e for e in errs) / len(errs)) if errs else float("nan")
mx = max(errs) if errs else float("nan")
rej = ", ".join(f"{k}: {v}" for k, v in sorted(reasons.items())) or "none"
pct = f"{det}/{vis} ({100.0 * det / vis:.0f} %)" if vis else "0/0"
print(f"| {effect} | `{print_}` / `{sensor}` | {pct} | {rej} | {rms:.3f} / {mx:.3f} |")
PY
done
