#!/usr/bin/env bash
# The README's two commands: the first builds the netvmo target alone and runs the demo, the
# second (build everything, run every test) is what .ci/run runs, verbatim, as one of its lines.
# Run by ctest (test Docs.CiRunsTheReadmesTestCommand).
set -u
cd "$(dirname "${BASH_SOURCE[0]}")/.."
mapfile -t cmds < <(awk '/^```sh$/ { code = 1; next } /^```/ { code = 0 } code' README.md | head -2)
if [ ${#cmds[@]} -ne 2 ]; then
  echo "check_readme_commands: README.md must start with two \`\`\`sh blocks of one command each"
  exit 1
fi
bad=0
case "${cmds[0]}" in
  *"cmake --build build -j2 --target netvmo && build/netvmo demo") ;;
  *) echo "README.md's first command does not build the netvmo target alone before the demo: ${cmds[0]}"
     bad=1 ;;
esac
if ! grep -qxF -- "${cmds[1]}" .ci/run; then
  echo ".ci/run does not run README.md's test command verbatim: ${cmds[1]}"
  bad=1
fi
[ "$bad" -eq 0 ] && echo "check_readme_commands: the demo command builds netvmo alone; .ci/run runs the test command"
exit "$bad"
