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
existing=()
for f in "${files[@]}"; do [ -f "$f" ] && existing+=("$f"); done
# One clang-format process for the whole tree (one per file spent half a minute starting up);
# --Werror reports each unformatted place as FILE:LINE:COL: error: ...
report=$(clang-format --dry-run --Werror "${existing[@]}" 2>&1)
rc=$?
mapfile -t unformatted < <(printf '%s\n' "$report" | sed -n 's/^\([^:]*\):[0-9]*:[0-9]*: error: .*/\1/p' | sort -u)
for f in "${unformatted[@]}"; do echo "not formatted: $f"; done
bad=${#unformatted[@]}
if [ "$rc" -ne 0 ] && [ "$bad" -eq 0 ]; then
  echo "check_format: clang-format failed: $(printf '%s\n' "$report" | head -1)"
  exit 1
fi
if [ "$bad" -ne 0 ]; then
  echo "check_format: $bad of ${#files[@]} files differ from .clang-format; fix with: clang-format -i FILE"
  exit 1
fi
echo "check_format: all ${#files[@]} files follow .clang-format ($(clang-format --version | head -1))"
