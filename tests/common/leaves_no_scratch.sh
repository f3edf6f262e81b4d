#!/usr/bin/env bash
# Usage: leaves_no_scratch.sh TEST_BINARY GTEST_FILTER
# Runs the GoogleTest cases of GTEST_FILTER (cases that make scratch folders) with TMPDIR set to an
# empty folder of its own and fails when they pass but leave anything in it (test_util.hpp,
# ScratchFolders).
set -u
binary=$1 filter=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
if ! TMPDIR=$tmp timeout 300 "$binary" --gtest_filter="$filter" --gtest_brief=1; then
  echo "leaves_no_scratch: $filter failed"
  exit 1
fi
made=$(find "$tmp" -mindepth 1 -maxdepth 1)
if [ -n "$made" ]; then
  echo "leaves_no_scratch: $filter passed and left: $made"
  exit 1
fi
echo "leaves_no_scratch: $filter passed and left nothing in TMPDIR"
