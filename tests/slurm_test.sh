#!/usr/bin/env bash
# `pp5sim sweep --slurm` on a real single-node Slurm: starts munged, slurmctld and slurmd
# from a minimal configuration in a scratch folder (nothing is installed and nothing outside
# that folder is touched; the daemons listen on two free ports of this host), submits the
# generated script, waits for the job array and the dependent aggregation, and checks the
# aggregated CSV against the grid. Usage: tests/slurm_test.sh PP5SIM
# Needs Debian's slurm-wlm and munge (scripts/install-deps.sh slurm) and root (slurmd starts
# jobs as their user); CMake registers it in ctest only when those are present.
# Where a single-node Slurm cannot start (no root, a host name that does not resolve, a
# daemon that refuses to start, e.g. for want of cgroups, a node that never becomes idle) it
# skips (status 77) and says why. It never hangs: every wait is bounded, and every Slurm
# client call has a time limit (PP5_SLURM_CALL_SECONDS, 20).
set -u
source "$(dirname "$0")/cli_lib.sh"
bin=$(readlink -f "$bin")
for tool in munged mungekey slurmctld slurmd sbatch squeue sinfo python3; do
  command -v "$tool" > /dev/null || { echo "SKIP: $tool not found (scripts/install-deps.sh slurm)"; exit 77; }
done
[ "$(id -u)" -eq 0 ] || { echo "SKIP: the single-node Slurm runs its daemons as root"; exit 77; }
skip() { echo "SKIP: a single-node Slurm cannot start here: $*"; exit 77; }
call_seconds="${PP5_SLURM_CALL_SECONDS:-20}"
# A Slurm client call with a time limit (a client whose controller does not answer retries).
slurm_call() { timeout "$call_seconds" "$@"; }

started=$(date +%s)
chmod 755 "$tmp"
host=$(hostname)
[ -n "$host" ] || skip "the host has no name (slurmd names its node after it)"
getent hosts "$host" > /dev/null \
  || skip "the host name '$host' does not resolve (add it to /etc/hosts); slurmctld and slurmd need it"
pids=()
stop_daemons() {
  for pid in "${pids[@]}"; do kill "$pid" 2> /dev/null; done
  for pid in "${pids[@]}"; do
    for _ in $(seq 50); do kill -0 "$pid" 2> /dev/null || break; sleep 0.1; done
  done
  rm -rf "$tmp"
}
trap stop_daemons EXIT

timeout 30 mungekey -c -k "$tmp/munge.key" || skip "mungekey could not make a key"
chmod 400 "$tmp/munge.key"
timeout 30 munged --key-file="$tmp/munge.key" --socket="$tmp/munge.socket" \
  --pid-file="$tmp/munged.pid" --log-file="$tmp/munged.log" --seed-file="$tmp/munge.seed" \
  || skip "munged did not start: $(tail -3 "$tmp/munged.log" 2>/dev/null)"
for _ in $(seq 50); do [ -s "$tmp/munged.pid" ] && break; sleep 0.1; done
[ -s "$tmp/munged.pid" ] || skip "munged wrote no pid file"
pids+=("$(cat "$tmp/munged.pid")")

mkdir -p "$tmp/state" "$tmp/spool"
# Two ports nobody listens on, so that runs from several checkouts do not meet.
read -r ctld_port slurmd_port < <(python3 -c '
import socket
s = [socket.socket() for _ in range(2)]
for x in s: x.bind(("", 0))
print(*[x.getsockname()[1] for x in s])') || fail "no free ports"
cat > "$tmp/slurm.conf" <<CONF
ClusterName=pp5test
SlurmctldHost=$host
SlurmUser=root
SlurmdUser=root
SlurmctldPort=$ctld_port
SlurmdPort=$slurmd_port
AuthType=auth/munge
AuthInfo=socket=$tmp/munge.socket
CredType=cred/munge
StateSaveLocation=$tmp/state
SlurmdSpoolDir=$tmp/spool
SlurmctldPidFile=$tmp/slurmctld.pid
SlurmdPidFile=$tmp/slurmd.pid
SlurmctldLogFile=$tmp/slurmctld.log
SlurmdLogFile=$tmp/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
SchedulerType=sched/backfill
SelectType=select/cons_tres
SelectTypeParameters=CR_CPU
ReturnToService=2
MpiDefault=none
SwitchType=switch/none
NodeName=$host CPUs=2 State=UNKNOWN
PartitionName=pp5 Nodes=$host Default=YES MaxTime=INFINITE State=UP
CONF
export SLURM_CONF="$tmp/slurm.conf"
timeout 30 slurmctld -f "$SLURM_CONF" 2> "$tmp/slurmctld.err" \
  || skip "slurmctld did not start: $(tail -3 "$tmp/slurmctld.err"; tail -5 "$tmp/slurmctld.log" 2>/dev/null)"
for _ in $(seq 50); do [ -s "$tmp/slurmctld.pid" ] && break; sleep 0.1; done
[ -s "$tmp/slurmctld.pid" ] || skip "slurmctld wrote no pid file: $(tail -5 "$tmp/slurmctld.log" 2>/dev/null)"
pids+=("$(cat "$tmp/slurmctld.pid")")
timeout 30 slurmd -f "$SLURM_CONF" 2> "$tmp/slurmd.err" \
  || skip "slurmd did not start (cgroups or the node's name?): $(tail -3 "$tmp/slurmd.err"; tail -5 "$tmp/slurmd.log" 2>/dev/null)"
for _ in $(seq 50); do [ -s "$tmp/slurmd.pid" ] && break; sleep 0.1; done
[ -s "$tmp/slurmd.pid" ] || skip "slurmd wrote no pid file: $(tail -5 "$tmp/slurmd.log" 2>/dev/null)"
pids+=("$(cat "$tmp/slurmd.pid")")
for _ in $(seq 100); do slurm_call sinfo -h -o %T 2> /dev/null | grep -q idle && break; sleep 0.2; done
slurm_call sinfo -h -o %T 2> /dev/null | grep -q idle \
  || skip "the node never became idle: $(slurm_call sinfo 2>&1); $(tail -3 "$tmp/slurmd.log" 2>/dev/null)"

# A 2 x 2 grid of a small scene: four array tasks, then the aggregation.
cd "$tmp"
"$bin" sweep --scene two-triangles --set screen.width=128 --set screen.height=128 \
  --grid gp.count=1,2 --grid renderer.count=1,2 --out sweep --slurm submit.sh > gen.txt \
  || fail "sweep --slurm: $(cat gen.txt)"
[ -x submit.sh ] || fail "submit.sh is not executable"
[ "$(wc -l < sweep/commands.txt)" -eq 4 ] || fail "commands.txt: $(cat sweep/commands.txt)"
grep -q -- "--array=0-3" submit.sh || fail "submit.sh has no array of 4 tasks"
timeout 60 bash submit.sh > submitted.txt || fail "submitting: $(cat submitted.txt)"
read -r array aggregate < sweep/slurm-jobs.txt || fail "no job ids"

# Wait (at most 3 minutes) until both jobs have left the queue.
deadline=$(($(date +%s) + 180))
while [ "$(date +%s)" -lt "$deadline" ]; do
  [ -z "$(slurm_call squeue -h -j "$array,$aggregate" 2> /dev/null)" ] && [ -s sweep/sweep.csv ] && break
  sleep 0.2
done
[ -z "$(slurm_call squeue -h -j "$array,$aggregate" 2> /dev/null)" ] && [ -s sweep/sweep.csv ] \
  || fail "the jobs did not finish: $(slurm_call squeue 2>&1); $(cat sweep/slurm-*.out 2>&1 | tail -20)"

# One row per grid point, with the swept keys, and each run's frame time.
csv=sweep/sweep.csv
[ "$(wc -l < "$csv")" -eq 5 ] || fail "expected a header and 4 rows: $(cat "$csv")"
head -1 "$csv" | grep -q "^gp.count,renderer.count,frame_seconds" || fail "header: $(head -1 "$csv")"
for point in 1,1 1,2 2,1 2,2; do
  grep -q "^$point," "$csv" || fail "no row for $point: $(cat "$csv")"
done
grep -q '<html' sweep/report.html 2>/dev/null || fail "the aggregate job wrote no report.html"
for d in sweep/gp.count-*_renderer.count-*; do
  [ -s "$d/stats.json" ] || fail "no stats.json in $d"
done
# The aggregated rows are those a local sweep gives (the frame time is deterministic).
"$bin" sweep --scene two-triangles --set screen.width=128 --set screen.height=128 \
  --grid gp.count=1,2 --grid renderer.count=1,2 --out local > /dev/null 2>&1 || fail "local sweep"
"$bin" sweep aggregate local -o local.csv > /dev/null || fail "local aggregate"
diff <(cut -d, -f1-3 "$csv") <(cut -d, -f1-3 local.csv) > /dev/null \
  || fail "Slurm and local sweeps differ: $(diff "$csv" local.csv)"
echo "slurm_test: passed in $(($(date +%s) - started)) s"
