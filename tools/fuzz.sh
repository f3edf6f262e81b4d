#!/usr/bin/env bash
# Runs every libFuzzer target of BUILD_DIR (default build-asan, made by tools/sanitize.sh) for
# SECONDS_PER_TARGET (default 30), one after the other, starting from the checked-in seed corpus
# tests/fuzz/corpus/<target>/ and dictionary tests/fuzz/dict/<target>.dict. Fails on any crash,
# leak, undefined behaviour, timeout (> 10 s per input) or out-of-memory (> 2048 MB): the input
# that did it is saved in OUT/crashes/ (printed), with the log in OUT/logs/. New inputs found
# go to OUT/corpus/<target>/ (the seed corpus is not modified). Prints each target's executions.
# With FUZZ_SEED set, every target starts from that libFuzzer seed, so a run repeats the same
# inputs (CI sets it: a bounded CI run checks a known sequence and never fails on a finding that a
# longer run has not made first; fuzz longer without it to explore). With FUZZ_RUNS=N each target
# stops after N executions instead (SECONDS_PER_TARGET is then its time cap), e.g.
#   FUZZ_RUNS=1000000 tools/fuzz.sh 3600        (docs/hardening.md's goal: 10^6 executions per target)
# FUZZ_TARGETS="a b" runs only those targets; FUZZ_JOBS=N runs N targets at a time (default 1;
# each target is one process on one core).
# Usage: [FUZZ_SEED=N] [FUZZ_RUNS=N] [FUZZ_TARGETS=...] tools/fuzz.sh [SECONDS_PER_TARGET] [BUILD_DIR] [OUT]
set -euo pipefail
cd "$(dirname "$0")/.."
seconds=${1:-30}
build=${2:-build-asan}
out=${3:-$build/fuzz-out}
src=tests/fuzz
export ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1:abort_on_error=1:strict_string_checks=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
export LSAN_OPTIONS=${LSAN_OPTIONS:-suppressions=$PWD/tools/lsan.supp:print_suppressions=0}

shopt -s nullglob
targets=("$build"/tests/fuzz/fuzz_*)
if [ ${#targets[@]} -eq 0 ]; then
  echo "fuzz.sh: no fuzz targets in $build/tests/fuzz (build with tools/sanitize.sh first)" >&2
  exit 1
fi
mkdir -p "$out/crashes" "$out/logs"
jobs=${FUZZ_JOBS:-1}
runs=()
[ -n "${FUZZ_RUNS:-}" ] && runs=(-runs="$FUZZ_RUNS")
# fuzz_one BIN: runs one target, prints its line, exits non-zero (with the report's first lines)
# when it found something.
fuzz_one() {
  local bin=$1 name=${1##*/fuzz_}
  mkdir -p "$out/corpus/$name"
  local dict=() seed=()
  [ -n "${FUZZ_SEED:-}" ] && seed=(-seed="$FUZZ_SEED")
  [ -f "$src/dict/$name.dict" ] && dict=(-dict="$src/dict/$name.dict")
  local log="$out/logs/$name.log" t0 rc=0 execs
  t0=$(date +%s)
  "$bin" -max_total_time="$seconds" -timeout=10 -rss_limit_mb=2048 -max_len=16384 \
    -close_fd_mask=1 -print_final_stats=1 -artifact_prefix="$out/crashes/$name-" "${dict[@]}" "${seed[@]}" "${runs[@]}" \
    "$out/corpus/$name" "$src/corpus/$name" >"$log" 2>&1 || rc=$?
  execs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$log" | tail -1)
  echo "fuzz.sh: $name: ${execs:-?} executions in $(($(date +%s) - t0)) s, exit $rc"
  if [ "$rc" -ne 0 ]; then
    grep -E "ERROR|runtime error|SUMMARY|Test unit written" "$log" | head -5 || true
    return 1
  fi
}
selected=()
for bin in "${targets[@]}"; do
  name=${bin##*/fuzz_}
  if [ -n "${FUZZ_TARGETS:-}" ] && [[ " $FUZZ_TARGETS " != *" $name "* ]]; then continue; fi
  selected+=("$bin")
done
failed=()
pids=()
names=()
# wait_one: waits for the oldest running target and records it when it failed.
wait_one() {
  if ! wait "${pids[0]}"; then failed+=("${names[0]}"); fi
  pids=("${pids[@]:1}")
  names=("${names[@]:1}")
}
for bin in "${selected[@]}"; do
  [ ${#pids[@]} -ge "$jobs" ] && wait_one
  fuzz_one "$bin" &
  pids+=($!)
  names+=("${bin##*/fuzz_}")
done
while [ ${#pids[@]} -gt 0 ]; do wait_one; done
if [ ${#failed[@]} -ne 0 ]; then
  echo "fuzz.sh: FAILED: ${failed[*]} (inputs in $out/crashes/, logs in $out/logs/)" >&2
  exit 1
fi
echo "fuzz.sh: no failure (${seconds} s cap a target${FUZZ_RUNS:+, $FUZZ_RUNS executions a target})"
