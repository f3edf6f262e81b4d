#!/usr/bin/env bash
# pipeline/README.md lists every pipeline header (its table's first column, `dir/name.hpp`).
# Exits 1 naming each header it does not list.
set -euo pipefail
cd "$(dirname "$0")/../pipeline"
missing=0
while read -r h; do
  if ! grep -qF "\`$h\`" README.md; then
    echo "check_header_list: pipeline/README.md does not list $h" >&2
    missing=1
  fi
done < <(cd include/netvmo/pipeline && find . -name '*.hpp' | sed 's|^\./||' | sort)
[ "$missing" = 0 ] && echo "check_header_list: every pipeline header is listed in pipeline/README.md"
exit "$missing"
