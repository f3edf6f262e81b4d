#!/usr/bin/env bash
# Lists every tracked C++ file that does not follow the root .clang-format and fails if there is
# one. Run by ctest (test Format.TreeFollowsClangFormat). The version is Debian 12's
# clang-format 14; other versions may format some constructs differently.
set -u
cd "$(dirname "$0")/.."
command -v clang-format >/dev/null ||
  { echo "check_format: clang-format is not installed (apt-get install clang-format)"; exit 1; }
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files '*.cpp' '*.hpp' '*.h')
else
  mapfile -t files < <(find observer render pipeline tools tests -name '*.cpp' -o -name '*.hpp')
fi
bad=0
for f in "${files[@]}"; do
  [ -f "$f" ] || continue
  if ! clang-format --dry-run --Werror "$f" >/dev/null 2>&1; then
    echo "not formatted: $f"
    bad=$((bad + 1))
  fi
done
if [ "$bad" -ne 0 ]; then
  echo "check_format: $bad of ${#files[@]} files differ from .clang-format; fix with: clang-format -i FILE"
  exit 1
fi
echo "check_format: all ${#files[@]} files follow .clang-format ($(clang-format --version | head -1))"
