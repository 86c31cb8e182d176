#!/usr/bin/env bash
# The script `pp5sim sweep --slurm` writes, run for real with a stub `sbatch` that does what
# Slurm would (runs the array's tasks and the wrapped aggregation at once, in --chdir, with
# --output's file-name pattern expanded), with every string that reaches the script made as
# hostile as a file name can be: nothing in them may run, and every run must still land in
# the folder named. Usage: tests/slurm_script_cli_test.sh PP5SIM
. "$(dirname "$0")/cli_lib.sh"
bin=$(readlink -f "$bin")
command -v python3 >/dev/null || { echo "SKIP: python3 not found"; exit 77; }
mkdir -p "$tmp/stub" "$tmp/work"
cat > "$tmp/stub/sbatch" <<'STUB'
#!/usr/bin/env python3
# A stand-in for Slurm's sbatch: runs the job at once and prints "JOBID" (--parsable).
import os, subprocess, sys
args, opts = sys.argv[1:], {}
for a in args:
    if a.startswith("--") and "=" in a:
        k, v = a[2:].split("=", 1); opts[k] = v
with open(os.environ["STUB_LOG"], "a") as log:
    log.write(repr(args) + "\n")
state = os.environ["STUB_LOG"] + ".next"
job = int(open(state).read()) if os.path.exists(state) else 100
open(state, "w").write(str(job + 1))
def pattern(p, task):  # Slurm's file-name pattern: %A %a %j %%
    out, k = "", 0
    while k < len(p):
        if p[k] == "%" and k + 1 < len(p):
            c = p[k + 1]; k += 2
            out += {"A": str(job), "a": str(task), "j": str(job), "%": "%"}.get(c, "%" + c)
        else:
            out += p[k]; k += 1
    return out
cwd = opts.get("chdir", os.getcwd())
if "wrap" in opts:
    script, tasks = "#!/bin/sh\n" + opts["wrap"] + "\n", [0]
else:
    script = sys.stdin.read()
    first, last = opts["array"].split("-")
    tasks = range(int(first), int(last) + 1)
for t in tasks:
    env = dict(os.environ, SLURM_ARRAY_TASK_ID=str(t), SLURM_JOB_ID=str(job))
    with open(os.path.join(cwd, pattern(opts["output"], t)), "w") as out:
        r = subprocess.run(["bash", "-c", script], cwd=cwd, env=env, stdout=out, stderr=out)
    if r.returncode != 0:
        sys.exit("stub sbatch: task %d failed" % t)
print(job)
STUB
chmod +x "$tmp/stub/sbatch"
export STUB_LOG="$tmp/sbatch.log"

# A folder name with a space, quotes, a command substitution, backquotes, a glob, a
# semicolon and Slurm's own pattern characters.
weird='we ird $(touch PWNED1) `touch PWNED2` '"'"'q'"'"' "d" ; touch PWNED3 * %A 100%'
cd "$tmp/work" || fail "no work folder"
"$bin" sweep --scene two-triangles --set screen.width=128 --set screen.height=128 \
  --set 'frame.highlight_opacity=128' --grid gp.count=1,2 --out "$weird" --slurm "$weird.sh" \
  >/dev/null || fail "sweep --slurm with a hostile folder name failed"
[ "$(wc -l < "$weird/commands.txt")" -eq 2 ] || fail "commands.txt is not one command per line"
PATH="$tmp/stub:$PATH" bash "$weird.sh" > "$tmp/submit.log" 2>&1 || fail "the script failed: $(cat "$tmp/submit.log")"
grep -q "submitted job array 100 (2 tasks) and aggregate job 101" "$tmp/submit.log" \
  || fail "the script said: $(cat "$tmp/submit.log")"
[ -z "$(find "$tmp" -name 'PWNED*')" ] || fail "a string in the script ran as a command: $(find "$tmp" -name 'PWNED*')"
for run in gp.count-1 gp.count-2; do
  [ -s "$weird/$run/stats.json" ] || fail "task $run did not write into the folder named"
done
[ "$(grep -c . "$weird/sweep.csv")" -eq 3 ] || fail "sweep.csv: $(cat "$weird/sweep.csv")"
# The aggregate job writes the sweep's report too.
grep -q '<html' "$weird/report.html" 2>/dev/null || fail "the aggregate job wrote no report.html"
# Slurm's logs land in the folder, with the folder's own '%' kept as it is.
[ -e "$weird/slurm-100_0.out" ] && [ -e "$weird/slurm-aggregate-101.out" ] \
  || fail "sbatch --output did not keep the folder's '%': $(ls "$tmp/work")"
[ "$(cat "$weird/slurm-jobs.txt")" = "100 101" ] || fail "slurm-jobs.txt: $(cat "$weird/slurm-jobs.txt")"

# A newline (or any control character) in a string that reaches the script is refused,
# and nothing is written.
nl=$'a\nrm -rf x'
expect_error "--out 'a\\\\nrm -rf x.*': holds a control character (a newline)" sweep \
  --scene two-triangles --grid gp.count=1,2 --out "$nl" --slurm nl.sh
[ -e nl.sh ] && fail "nl.sh written although --out was refused"
[ -e "$nl" ] && fail "the folder was made although --out was refused"
expect_error "--out 'x\\\\x1b\[0m/gp.count-1': holds a control character (byte 0x1b)" sweep \
  --scene two-triangles --grid gp.count=1,2 --out $'x\e[0m' --print-commands
expect_error "holds a control character" sweep --scene two-triangles --grid gp.count=1,2 \
  --out "$nl" --print-commands
echo "slurm_script_cli: all checks passed"
