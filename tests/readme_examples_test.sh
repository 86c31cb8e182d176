#!/usr/bin/env bash
# Every pp5sim command shown in the code blocks of README.md, traces/README.md and docs/ runs
# as written: each is run from a scratch folder that sees the checkout's examples/, firmware/
# and tests/ and a build/pp5sim that is the binary under test, and must exit 0 (the one
# documented exception: `extremes --scene torus` reports its failing case with status 1).
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
# A "what if" (a render that changes the machine, the firmware or the level) must name its own
# --out: without it, it would write into the scene's folder over the plain run, and
# `pp5sim stats out/SCENE/stats.json` would show whichever ran last.
commands=$(python3 - "$root" <<'PY'
import glob, os, re, sys
root = sys.argv[1]
files = ["README.md", "traces/README.md"] + sorted(os.path.relpath(f, root)
                               for f in glob.glob(os.path.join(root, "docs", "**", "*.md"), recursive=True))
bad = []
for name in files:
    text = open(os.path.join(root, name)).read()
    for block in re.findall(r"```[a-z]*\n(.*?)```", text, re.S):
        for line in block.splitlines():
            line = line.split(" #")[0].strip()
            if line.startswith("build/pp5sim") and line.endswith("\\"):
                bad.append(f"{name}: a command continued with a backslash (write it on one line): {line}")
                continue
            for command in line.split(", "):
                if not command.startswith("build/pp5sim"):
                    continue
                words = command.split()
                renders = len(words) == 1 or words[1] == "render" or words[1].startswith("-")
                what_if = any(w in ("--set", "--config", "--param", "--fidelity", "--firmware", "-f",
                                    "--order", "--tessellation") for w in words)
                if renders and what_if and "--out" not in words and "-o" not in words:
                    bad.append(f"{name}: {command}")
                print(command)
if bad:
    sys.stderr.write("commands the docs test cannot run as written (a what-if without its own --out, or a continued line):\n  " + "\n  ".join(bad) + "\n")
    sys.exit(1)
PY
)
[ $? -eq 0 ] || { echo "FAIL: give each of these its own --out folder (above)"; exit 1; }
[ -n "$commands" ] || { echo "FAIL: no commands found in README.md, traces/README.md and docs/"; exit 1; }
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
