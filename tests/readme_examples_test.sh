#!/usr/bin/env bash
# Every pp5sim command shown in README.md's code blocks runs as written (issue 18): each is
# run from a scratch folder that sees the checkout's examples/, firmware/ and tests/ and a
# build/pp5sim that is the binary under test, and must exit 0 (the one documented exception:
# `extremes --scene torus` reports its failing case with status 1).
#   tests/readme_examples_test.sh PP5SIM [--all]
# Without --all the `highlight` examples (minutes each) are listed, not run; CI runs the rest.
set -u
bin="$1"
all="${2:-}"
root="$(cd "$(dirname "$0")/.." && pwd)"
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$tmp/build"
ln -s "$bin" "$tmp/build/pp5sim"
for d in examples firmware tests; do ln -s "$root/$d" "$tmp/$d"; done
commands=$(python3 - "$root/README.md" <<'PY'
import re, sys
text = open(sys.argv[1]).read()
for block in re.findall(r"```[a-z]*\n(.*?)```", text, re.S):
    for line in block.splitlines():
        line = line.split("#")[0].strip()
        for command in line.split(", "):
            if command.startswith("build/pp5sim"):
                print(command)
PY
)
[ -n "$commands" ] || { echo "FAIL: no commands found in README.md"; exit 1; }
ran=0 skipped=0 failed=0
while IFS= read -r command; do
  if [[ "$command" =~ ^build/pp5sim\ highlight( |$) && "$all" != "--all" ]]; then
    echo "skipped (run with --all): $command"
    skipped=$((skipped + 1))
    continue
  fi
  expected=0
  [[ "$command" == "build/pp5sim extremes --scene torus" ]] && expected=1
  (cd "$tmp" && eval "$command") >"$tmp/log" 2>&1
  status=$?
  if [ "$status" -ne "$expected" ]; then
    echo "FAIL ($status, expected $expected): $command"
    tail -5 "$tmp/log"
    failed=$((failed + 1))
  fi
  ran=$((ran + 1))
done <<<"$commands"
echo "readme examples: $ran run, $skipped skipped, $failed failed"
[ "$failed" -eq 0 ]
