#!/usr/bin/env bash
# Checks every relative link of the tracked Markdown files: each `[text](target)` or
# `![figure](target)` whose target is not a URL must name a file or folder that exists, relative
# to the file that holds the link, and a `#anchor` (alone or after a .md target) must name one of
# that page's headings, spelt as GitHub spells heading anchors. Run by ctest (test
# Docs.RelativeLinksResolve). Prints each broken link as FILE:LINE: TARGET and fails if there is one.
set -u
export LC_ALL=C.UTF-8
cd "$(dirname "${BASH_SOURCE[0]}")/.."
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files --cached --others --exclude-standard '*.md')
else
  mapfile -t files < <(find . -name '*.md' -not -path './build*' | sed 's|^\./||')
fi

# anchors FILE: the anchors of FILE's headings, one a line (duplicates numbered -1, -2, ...).
anchors() {
  sed -n -E '/^```/,/^```/d; s/^#{1,6} +(.*[^ ])[ #]*$/\1/p' "$1" |
    sed -E 's/[A-Z]/\L&/g; s/[^[:alnum:] _-]//g; s/ /-/g' |
    awk '{ n = seen[$0]++; if (n) print $0 "-" n; else print $0 }'
}

bad=0
links=0
for f in "${files[@]}"; do
  [ -f "$f" ] || continue
  dir=$(dirname "$f")
  # Links outside fenced code blocks and inline code spans.
  while IFS=: read -r line target; do
    links=$((links + 1))
    case "$target" in
      http://* | https://* | mailto:*) continue ;;
    esac
    path=${target%%#*}
    anchor=
    [[ "$target" == *"#"* ]] && anchor=${target#*#}
    if [ -n "$path" ]; then
      resolved="$dir/$path"
      if [ ! -e "$resolved" ]; then
        echo "$f:$line: $target (no such file: $resolved)"
        bad=$((bad + 1))
        continue
      fi
    else
      resolved=$f
    fi
    if [ -n "$anchor" ] && [[ "$resolved" == *.md ]]; then
      if ! anchors "$resolved" | grep -qxF -- "$anchor"; then
        echo "$f:$line: $target (no heading with anchor #$anchor in $resolved)"
        bad=$((bad + 1))
      fi
    fi
  done < <(awk '/^```/ { code = !code; next } !code { gsub(/`[^`]*`/, ""); print NR ":" $0 }' "$f" |
             grep -oE '^[0-9]+:|\]\([^) ]+\)' |
             awk '/^[0-9]+:$/ { n = substr($0, 1, length($0) - 1); next } { print n ":" substr($0, 3, length($0) - 3) }')
done
if [ "$bad" -ne 0 ]; then
  echo "check_links: $bad of $links relative links in ${#files[@]} Markdown files are broken"
  exit 1
fi
echo "check_links: all $links links in ${#files[@]} Markdown files resolve"
