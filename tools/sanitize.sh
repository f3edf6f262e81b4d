#!/usr/bin/env bash
# The sanitizer build (docs/hardening.md, "Sanitizers and fuzzing"): configures BUILD_DIR (default build-asan) with clang,
# AddressSanitizer + UndefinedBehaviorSanitizer (any report is fatal) and the libFuzzer targets,
# builds everything and runs the whole ctest suite there (the fuzzers' corpora included).
# Prints the time of each part. Usage: tools/sanitize.sh [BUILD_DIR [CTEST_ARGS...]]
# (e.g. -E REGEX to leave tests out: .ci/run does, see docs/hardening.md, "Commands").
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-asan}
shift || true
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tools/lsan.supp:print_suppressions=0}
# OpenCV's gphoto2 camera backend, tried whenever a VideoCapture opens a file, loads libgphoto2's
# libusb port driver, which leaks its device list (LeakSanitizer; the driver is unloaded again, so
# no suppression can name it). netvmo opens files only: the backend is switched off here.
export OPENCV_VIDEOIO_PRIORITY_GPHOTO2=0

TIMEFORMAT="sanitize.sh: %R s wall, %U s user CPU, %S s system CPU"
echo "sanitize.sh: configure and build ($build)"
time {
  cmake -S . -B "$build" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DNETVMO_FUZZ=ON -DNETVMO_BUILD_BENCHMARKS=OFF "${launcher[@]}"
  cmake --build "$build" -j2
}
echo "sanitize.sh: the whole test suite under ASan + UBSan"
time ctest --test-dir "$build" --output-on-failure -j2 "$@"
