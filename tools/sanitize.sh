#!/usr/bin/env bash
# The sanitizer build (docs/hardening.md, "Sanitizers and fuzzing"): configures BUILD_DIR (default
# build-asan) with clang, AddressSanitizer + UndefinedBehaviorSanitizer (any report is fatal) and
# the libFuzzer targets, builds everything and runs the whole ctest suite there (the fuzzers'
# corpora included). Prints the time of each part.
# Usage: [SANITIZE_TARGETS="t1 t2"] [SANITIZE_EXCLUDE=REGEX] [SANITIZE_CMAKE_ARGS="-D..."]
#        tools/sanitize.sh [BUILD_DIR [CTEST_ARGS...]]
# With SANITIZE_TARGETS only those targets and every fuzz target are built, and only their tests
# run (.ci/run does so to stay within CI's time). SANITIZE_EXCLUDE leaves the tests it matches
# out; SANITIZE_CMAKE_ARGS go to cmake's configure; CTEST_ARGS go to ctest as they are.
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

# Line tables are all a sanitizer report's stack trace needs; full debug information (-g) made
# the build 15 % slower.
flags="-O2 -gline-tables-only -DNDEBUG"

read -r -a extra_cmake <<<"${SANITIZE_CMAKE_ARGS:-}"

TIMEFORMAT="sanitize.sh: %R s wall, %U s user CPU, %S s system CPU"
echo "sanitize.sh: configure and build ($build)"
time {
  cmake -S . -B "$build" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
    -DCMAKE_BUILD_TYPE=RelWithDebInfo -DNETVMO_FUZZ=ON -DNETVMO_BUILD_BENCHMARKS=OFF "${launcher[@]}" \
    "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=$flags" "-DCMAKE_C_FLAGS_RELWITHDEBINFO=$flags" \
    "${extra_cmake[@]}"
  if [ -n "${SANITIZE_TARGETS:-}" ]; then
    mapfile -t fuzzers < <(cmake --build "$build" --target help | sed -n 's/^\.\.\. \(fuzz_[a-z_]*\)$/\1/p')
    # shellcheck disable=SC2086
    cmake --build "$build" -j2 --target $SANITIZE_TARGETS "${fuzzers[@]}"
  else
    cmake --build "$build" -j2
  fi
}
exclude=${SANITIZE_EXCLUDE:-}
if [ -n "${SANITIZE_TARGETS:-}" ]; then
  # The test binaries not built are placeholders named <target>_NOT_BUILT in ctest.
  echo "sanitize.sh: the tests of $SANITIZE_TARGETS and the fuzz corpora under ASan + UBSan"
  time ctest --test-dir "$build" --output-on-failure -j2 -E "_NOT_BUILT\$${exclude:+|$exclude}" "$@"
else
  echo "sanitize.sh: the whole test suite under ASan + UBSan"
  time ctest --test-dir "$build" --output-on-failure -j2 ${exclude:+-E "$exclude"} "$@"
fi
