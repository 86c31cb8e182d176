#!/usr/bin/env python3
"""Runs every `python3 -c "..."` line of the given Markdown files (the README's front-door
example and the Python guide's) with this interpreter, and every ```python block of them,
each as it stands; fails naming the file and line of the first that fails. Usage:
run_readme_python.py FILE.md..."""
import os
import re
import shlex
import subprocess
import sys
import tempfile


def examples(path):
    lines = open(path, encoding="utf-8").read().splitlines()
    i = 0
    while i < len(lines):
        line = lines[i]
        if line.strip() == "```python":
            start = i + 1
            j = start
            while j < len(lines) and lines[j].strip() != "```":
                j += 1
            yield start, "block", "\n".join(lines[start:j])
            i = j + 1
            continue
        m = re.match(r"^\s*(?:PYTHONPATH=\S+\s+)?python3 -c (.*)$", line)
        if m:
            yield i + 1, "line", shlex.split(m.group(1))[0]
        i += 1


def main():
    failures = 0
    count = 0
    with tempfile.TemporaryDirectory(prefix="pp5-readme-py-") as scratch:
        for path in sys.argv[1:]:
            for line, kind, code in examples(path):
                count += 1
                r = subprocess.run([sys.executable, "-c", code], cwd=scratch,
                                   capture_output=True, text=True, stdin=subprocess.DEVNULL)
                if r.returncode != 0:
                    failures += 1
                    print(f"{path}:{line}: the {kind} failed:\n{code}\n{r.stderr}", file=sys.stderr)
    if count == 0:
        print("no python examples found", file=sys.stderr)
        return 1
    print(f"{count} python examples ran, {failures} failed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
