#!/usr/bin/env bash
# Installs netvmo's build and run dependencies from Debian 12's packages. Idempotent: does
# nothing when everything is already installed. Uses sudo when not run as root.
set -euo pipefail

packages=(
  build-essential cmake pkg-config
  libeigen3-dev libembree-dev libapriltag-dev libvisp-dev libopencv-dev
  libgtest-dev libbenchmark-dev libyaml-cpp-dev libcli11-dev nlohmann-json3-dev
  gnuplot-nox clang-format cyclonedds-dev cyclonedds-tools
  # netvmo calibrate's bundle adjustment and pose covariance (Ceres Solver).
  libceres-dev
  # rosbag2 bags as datasets (their sqlite3 storage).
  libsqlite3-dev
  # DDS Security's test PKI (netvmo security init: keys, certificates, signed documents).
  libssl-dev
  # Several machines emulated by the tests (tools/netns_run.sh): network namespaces, loss and
  # partitions in the kernel.
  iproute2 nftables
  # A real photo of printed tags every machine can have (ViSP's AprilTag.pgm, read in place by
  # the test RealPhotos.DeskPhoto*; GPL-2 data of Debian's ViSP packaging, not copied here).
  visp-images-data
  # The sanitizer and fuzzing build (tools/sanitize.sh, tools/fuzz.sh): clang 14, its
  # ASan/UBSan/libFuzzer runtimes (only recommended by clang, so named here) and llvm-symbolizer.
  clang libclang-rt-14-dev llvm
)

missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -eq 0 ]; then
  echo "netvmo: all ${#packages[@]} dependencies are installed"
  exit 0
fi

as_root=()
if [ "$(id -u)" -ne 0 ]; then
  command -v sudo >/dev/null || { echo "netvmo: run as root or install sudo to install: ${missing[*]}" >&2; exit 1; }
  as_root=(sudo)
fi
echo "netvmo: installing ${missing[*]}"
"${as_root[@]}" apt-get update -qq
DEBIAN_FRONTEND=noninteractive "${as_root[@]}" apt-get install -y -qq --no-install-recommends "${missing[@]}"
