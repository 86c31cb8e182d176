#!/usr/bin/env bash
# A new user's mistakes on the command line (issue 18): a sentence with a suggestion and exit
# status 2, never the argument parser's own codes; --version.
. "$(dirname "$0")/cli_lib.sh"
status_of() { "$bin" "$@" >/dev/null 2>&1; echo $?; }

expect_error "unknown command 'rendr'; did you mean 'render'?" rendr
expect_error "unknown option '--sceen'; did you mean '--scene'?" render --sceen torus
expect_error "unknown command 'frobnicate'" frobnicate
expect_error "--threads: Value 0 not in range 1 to 256" render --threads 0 --out "$tmp/x"
for args in "rendr" "render --sceen torus" "render --threads 0" "sweep --grid"; do
  # shellcheck disable=SC2086
  [ "$(status_of $args)" = 2 ] || fail "'$args' should exit 2, exited $(status_of $args)"
done
"$bin" --version | grep -q "^pp5sim [0-9]" || fail "--version printed: $("$bin" --version)"
[ "$(status_of --help)" = 0 ] || fail "--help should exit 0"
# The top-level --help lists each command on one line that fits a terminal; a command's own
# --help keeps its whole description.
"$bin" --help > "$tmp/help.txt"
for command in render sweep trace highlight extremes validate visible csg; do
  [ "$(grep -c "^  $command " "$tmp/help.txt")" = 1 ] || fail "--help: no one line for $command"
done
awk '!/^Usage:/ && length > 80 { print; bad = 1 } END { exit bad }' "$tmp/help.txt" \
  || fail "--help has lines wider than 80 columns"
"$bin" extremes --help | grep -q "pixel-centre ownership" || fail "extremes --help lost its description"
[ -e "$tmp/x" ] && fail "a usage error wrote output"
# A grid is walked, never held: a 26-million-point grid is refused at once, a 100,000-point
# one prints its commands without exhausting memory.
ten=1,2,3,4,5,6,7,8,9,10
expect_error "the grid has more than 1000000 points" sweep --grid gp.count=$ten \
  --grid renderer.count=$ten --grid ring.channels=$ten --grid ring.hop_latency_cycles=$ten \
  --grid evaluator.latency_cycles=$ten --grid renderer.packet_overhead_cycles=$ten,11,12,13,14,15,16,17,18,19,20,21,22,23,24,25,26 \
  --print-commands --out "$tmp/sweep"
# (AddressSanitizer reserves terabytes of address space, so under it no ulimit -v applies;
# gcc links its runtime as libasan.so, clang into the binary.)
if ldd "$bin" 2>/dev/null | grep -q libasan || grep -q __asan_init "$bin"; then
  limit=unlimited
else
  limit=$((2 * 1024 * 1024))
fi
lines=$( (ulimit -v $limit; "$bin" sweep --grid gp.count=$ten --grid renderer.count=$ten \
  --grid ring.channels=$ten --grid ring.hop_latency_cycles=$ten --grid evaluator.latency_cycles=$ten \
  --print-commands --out "$tmp/sweep") | wc -l)
[ "$lines" = 100000 ] || fail "a 100,000-point sweep printed $lines commands"
# A frame too large for the host is refused before anything is allocated, saying what to reduce
# (checked where an address-space limit can be set). The program must spill, so that every pixel
# has its backing store: the test data's spill.pp5 (the shipped programs fit since issue 17).
[ "$limit" = unlimited ] && { echo "usage_cli: all checks passed (memory limit not tested under ASan)"; exit 0; }
out=$( (ulimit -v $((2 * 1024 * 1024)); "$bin" render --set renderer.region_width=1024 \
  --set renderer.region_height=1024 --set renderer.backing_store_bits=65536 \
  --firmware "$(dirname "$0")/data/firmware/spill.pp5" \
  --set screen.width=1024 --out "$tmp/big") 2>&1) && fail "a 72 GiB frame ran under a 2 GiB limit"
echo "$out" | grep -q "this frame needs about .* GiB .* smaller renderer.backing_store_bits" \
  || fail "memory refusal said: $out"
[ -e "$tmp/big/frame.png" ] && fail "a refused frame wrote output"
echo "usage_cli: all checks passed"
