#!/usr/bin/env bash
# The sanitizer build (README "Hardening"): configures BUILD_DIR (default build-asan) with clang,
# AddressSanitizer + UndefinedBehaviorSanitizer (any report is fatal) and the libFuzzer targets,
# builds everything and runs the whole ctest suite there (the fuzzers' corpora included).
# Prints the time of each part. Usage: tools/sanitize.sh [BUILD_DIR]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build-asan}
launcher=()
if command -v ccache >/dev/null; then
  launcher=(-DCMAKE_C_COMPILER_LAUNCHER=ccache -DCMAKE_CXX_COMPILER_LAUNCHER=ccache)
fi
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tools/lsan.supp:print_suppressions=0}

t0=$(date +%s)
cmake -S . -B "$build" -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
  -DCMAKE_BUILD_TYPE=RelWithDebInfo -DNETVMO_FUZZ=ON -DNETVMO_BUILD_BENCHMARKS=OFF "${launcher[@]}"
cmake --build "$build" -j2
t1=$(date +%s)
ctest --test-dir "$build" --output-on-failure -j2
t2=$(date +%s)
echo "sanitize.sh: build $((t1 - t0)) s, tests $((t2 - t1)) s (ASan + UBSan, $build)"
