#!/usr/bin/env bash
# The fidelity levels' speed (issue 12, section 4), measured in one run as whole pp5sim
# processes: wall time including scene set-up, the simulation and the PNG. Prints ratios,
# never asserts them (a timed test would fail on a loaded machine):
#   - Banks (the torus at 1280 x 1024, threshold, gp.code=compiled) and the machine at full
#     speed (phong, gp.code=assembly): host wall time / simulated frame time, at bit and at
#     word; below 1 means the simulator drew the frame faster than the machine did.
#   - event / analytic host time at fidelity.pixels=none on the torus (the target is >= 100).
#   - a 1,000-point sweep of the torus (gp.count 1..40 x renderer.count 1..25) at
#     --fidelity timing and --fidelity analytic, split in two halves run at once (2 cores),
#     and the median point's timing-model host time at each level (the set-up replayed);
#   - first, the process's start-up and exit alone (pp5sim --version): the floor under all.
# Usage: bench/bench_fidelity.sh [build/pp5sim] [runs, default 3: each figure is the fastest]
set -euo pipefail
bin="${1:-build/pp5sim}"
runs="${2:-3}"
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT

now() { date +%s.%N; }
# fastest wall time of `runs` runs of a command, in seconds
fastest() {
  local best="" t0 t1 t
  for _ in $(seq "$runs"); do
    t0=$(now)
    "$@" >/dev/null
    t1=$(now)
    t=$(echo "$t1 - $t0" | bc -l)
    if [ -z "$best" ] || [ "$(echo "$t < $best" | bc -l)" = 1 ]; then best=$t; fi
  done
  echo "$best"
}
simulated() {  # the frame time a render wrote, in seconds
  python3 -c 'import json,sys; print("%.9f" % json.load(open(sys.argv[1]))["frame"]["simulated_seconds"])' \
    "$1/stats.json"
}

echo "pp5sim fidelity benchmark: $("$bin" --version), $(nproc) cores, fastest of $runs runs"
# The floor under every figure below: starting the process (loading its libraries) and
# leaving it, with nothing simulated.
printf 'process start-up and exit (pp5sim --version): %.3f s\n' "$(fastest "$bin" --version)"
echo
printf '%-34s %-6s %10s %12s %12s\n' configuration level "host s" "simulated s" "host/sim"
for config in "banks:threshold:compiled" "full-speed:phong:assembly"; do
  IFS=: read -r name program code <<<"$config"
  for level in bit word; do
    out="$scratch/$name-$level"
    host=$(fastest "$bin" render --firmware "$program" --set gp.code="$code" \
      --fidelity "$level" --threads 2 --out "$out")
    sim=$(simulated "$out")
    printf '%-34s %-6s %10.3f %12.6f %12.2f\n' "$name ($program, gp.code=$code)" "$level" \
      "$host" "$sim" "$(echo "$host / $sim" | bc -l)"
  done
done

echo
event=$(fastest "$bin" render --fidelity timing --out "$scratch/event")
analytic=$(fastest "$bin" render --fidelity analytic --out "$scratch/analytic")
# The process's own start-up (reading programs, building the scene) is in both; the
# simulation's own host time is in stats.json as host.seconds: the least of `runs` runs, like
# the wall times (one run's figure swings with the machine's load).
least_host_seconds() {
  local best="" t
  for k in $(seq "$runs"); do
    "$bin" render --fidelity "$1" --out "$scratch/host-$1-$k" >/dev/null
    t=$(python3 -c 'import json,sys; print("%.9f" % json.load(open(sys.argv[1]))["host"]["seconds"])' \
      "$scratch/host-$1-$k/stats.json")
    if [ -z "$best" ] || [ "$(echo "$t < $best" | bc -l)" = 1 ]; then best=$t; fi
  done
  echo "$best"
}
event_sim=$(least_host_seconds timing)
analytic_sim=$(least_host_seconds analytic)
printf 'torus, pixels=none: event %.3f s, analytic %.3f s whole process (%.1fx); ' \
  "$event" "$analytic" "$(echo "$event / $analytic" | bc -l)"
printf 'simulate_frame alone %.4f s vs %.4f s (%.1fx)\n' "$event_sim" "$analytic_sim" \
  "$(echo "$event_sim / $analytic_sim" | bc -l)"

echo
gps_a=$(seq -s, 1 20)
gps_b=$(seq -s, 21 40)
renderers=$(seq -s, 1 25)
for level in timing analytic; do
  t0=$(now)
  "$bin" sweep --fidelity "$level" --grid gp.count="$gps_a" --grid renderer.count="$renderers" \
    --out "$scratch/sweep-$level-a" 2>/dev/null >/dev/null &
  "$bin" sweep --fidelity "$level" --grid gp.count="$gps_b" --grid renderer.count="$renderers" \
    --out "$scratch/sweep-$level-b" 2>/dev/null >/dev/null &
  wait
  t1=$(now)
  printf '1,000-point sweep of the torus at --fidelity %-8s on 2 cores: %.1f s\n' "$level" \
    "$(echo "$t1 - $t0" | bc -l)"
done
# Per point, the timing model's own host time (host.timing_seconds: the analytic sums or the
# SystemC run, after the set-up each half's first point made and the rest replay).
median_point() {
  python3 - "$scratch/sweep-$1-a" "$scratch/sweep-$1-b" <<'PY'
import glob, json, sys
t = sorted(json.load(open(f))["host"]["timing_seconds"]
           for d in sys.argv[1:] for f in glob.glob(d + "/*/stats.json"))
print(f"{t[len(t) // 2]:.9f}")  # bc reads no exponent
PY
}
event_point=$(median_point timing)
analytic_point=$(median_point analytic)
printf 'a sweep point, median host.timing_seconds: event %.6f s, analytic %.6f s (%.1fx)\n' \
  "$event_point" "$analytic_point" "$(echo "$event_point / $analytic_point" | bc -l)"
