#!/usr/bin/env bash
# pp5sim animate and render --frames write their outputs as the frames run, staged in a
# private folder inside the output folder (.pp5-staging-PID-XXXXXX), and move them into place
# together at the end: a run that fails midway (a full disk, a file size limit, a folder it
# cannot write) or is interrupted leaves no output and no staging folder, and an earlier run's
# outputs as they were.
. "$(dirname "$0")/cli_lib.sh"
small=(--set screen.width=128 --set screen.height=128 --set renderer.count=2)
anim=(animate --scene torus --tessellation 24 12 "${small[@]}")
staging() { find "$1" -name '.pp5-staging-*' 2>/dev/null | head -1; }

# A run, then a second into the same folder that fails midway on a file size limit: the
# error names the file, and the first run's outputs are untouched, with no staging folder.
"$bin" "${anim[@]}" --frames 2 --out "$tmp/keep" >/dev/null 2>&1 || fail "first run failed"
cp -r "$tmp/keep" "$tmp/keep-before"
# stats.json and the timeline grow past 200 KB (ulimit -f counts KiB) a few frames in; every
# frame file stays below it.
out=$( (ulimit -f 200; "$bin" "${anim[@]}" --frames 40 --out "$tmp/keep" 2>&1) ) &&
  fail "a run past the file size limit succeeded"
echo "$out" | grep -Eq "keep/(timeline|stats).json: cannot write \(File too large\)" ||
  fail "ulimit -f said: $out"
echo "$out" | grep -q "^frame 3:" || fail "the run did not fail midway: $out"
diff -r "$tmp/keep" "$tmp/keep-before" >/dev/null || fail "the failed run changed the first run's outputs"
[ -z "$(staging "$tmp/keep")" ] || fail "a failed run left $(staging "$tmp/keep")"
# Into a new folder: nothing at all is left, not even the folder.
out=$( (ulimit -f 200; "$bin" "${anim[@]}" --frames 40 --out "$tmp/new/run" 2>&1) ) &&
  fail "a run past the file size limit succeeded"
[ -e "$tmp/new" ] && fail "a failed run left $(find "$tmp/new")"

# render --frames streams its timeline the same way.
out=$( (ulimit -f 200; "$bin" render --scene torus --tessellation 24 12 "${small[@]}" --frames 40 \
  --out "$tmp/rf" --timeline "$tmp/rf.json" 2>&1) ) && fail "render --frames past the limit succeeded"
echo "$out" | grep -q "rf.json: cannot write (File too large)" || fail "render --frames said: $out"
[ -e "$tmp/rf" ] || [ -e "$tmp/rf.json" ] && fail "render --frames left $(ls -d "$tmp"/rf*)"
[ -z "$(staging "$tmp")" ] || fail "render --frames left $(staging "$tmp")"

# Interrupted (SIGINT, SIGTERM) at any moment: no staging folder, no output, no new folder.
interrupted=0
for signal in INT TERM; do
  for delay in 0.05 0.3 0.8 1.5; do
    "$bin" "${anim[@]}" --frames 400 --out "$tmp/int/run" >/dev/null 2>&1 &
    pid=$!
    sleep "$delay"
    kill -$signal $pid 2>/dev/null
    if wait $pid; then  # finished before the signal
      rm -rf "$tmp/int"
      continue
    fi
    interrupted=$((interrupted + 1))
    [ -z "$(staging "$tmp/int")" ] || fail "SIG$signal after $delay s left $(staging "$tmp/int")"
    [ -e "$tmp/int" ] && fail "SIG$signal after $delay s left $(find "$tmp/int" | head -3)"
  done
done
[ $interrupted -ge 6 ] || fail "only $interrupted of 8 runs were interrupted (make them longer)"
# An interrupted run into an earlier run's folder leaves that run's outputs as they were.
"$bin" "${anim[@]}" --frames 400 --out "$tmp/keep" >/dev/null 2>&1 &
pid=$!
sleep 0.8
kill -TERM $pid
wait $pid && fail "the run ended before SIGTERM (make it longer)"
diff -r "$tmp/keep" "$tmp/keep-before" >/dev/null || fail "an interrupted run changed the outputs"
[ -z "$(staging "$tmp/keep")" ] || fail "an interrupted run left $(staging "$tmp/keep")"

# Two runs at once into different folders: each stages in its own folder, under a name of
# its own (the process id and a random part), and both finish complete. The commit pauses
# between moves (test hook) so that both staging folders can be seen.
PP5_TEST_COMMIT_PAUSE_MS=200 "$bin" "${anim[@]}" --frames 3 --out "$tmp/two-a" >/dev/null 2>&1 &
a=$!
PP5_TEST_COMMIT_PAUSE_MS=200 "$bin" "${anim[@]}" --frames 3 --out "$tmp/two-b" >/dev/null 2>&1 &
b=$!
seen_a="" seen_b=""
for _ in $(seq 1 200); do
  [ -z "$seen_a" ] && seen_a=$(staging "$tmp/two-a")
  [ -z "$seen_b" ] && seen_b=$(staging "$tmp/two-b")
  [ -n "$seen_a" ] && [ -n "$seen_b" ] && break
  sleep 0.02
done
wait $a || fail "run a failed"
wait $b || fail "run b failed"
[ -n "$seen_a" ] && [ -n "$seen_b" ] || fail "no staging folder seen ($seen_a, $seen_b)"
[ "$(basename "$seen_a")" != "$(basename "$seen_b")" ] || fail "both runs staged as $seen_a"
[[ "$(basename "$seen_a")" == .pp5-staging-$a-* ]] || fail "run a staged in $seen_a (pid $a)"
for d in two-a two-b; do
  [ -s "$tmp/$d/frame-0002.png" ] && [ -s "$tmp/$d/timeline.json" ] || fail "$d incomplete"
  [ -z "$(staging "$tmp/$d")" ] || fail "$d: $(staging "$tmp/$d") left"
done
cmp -s "$tmp/two-a/timeline.json" "$tmp/two-b/timeline.json" || fail "the two timelines differ"

# A full disk (a small tmpfs in a private mount namespace, where allowed) and a folder that
# cannot be written (read-only): an error naming the file or folder, nothing left.
if unshare --user --map-root-user --mount true 2>/dev/null; then
  out=$(unshare --user --map-root-user --mount sh -c '
    bin="$1"; dir="$2"; shift 2
    mkdir -p "$dir/disk" && mount -t tmpfs -o size=400k tmpfs "$dir/disk" || exit 90
    "$bin" "$@" --frames 40 --out "$dir/disk/run" 2>&1 && exit 91
    [ -e "$dir/disk/run" ] && exit 92
    mkdir "$dir/disk/ro" && mount -o remount,ro "$dir/disk" || exit 93
    "$bin" "$@" --frames 2 --out "$dir/disk/ro" 2>&1 && exit 94
    exit 0' sh "$bin" "$tmp" "${anim[@]}")
  status=$?
  [ $status -eq 0 ] || fail "full disk: step $status failed: $out"
  echo "$out" | grep -Eq "run/[a-z0-9.-]+: cannot write \(No space left on device\)" ||
    fail "full disk said: $out"
  echo "$out" | grep -q "ro: cannot create a staging folder for this run's outputs (Read-only file system)" ||
    fail "read-only folder said: $out"
else
  echo "animate_output_cli: full-disk and read-only checks skipped (no unprivileged mount namespace)"
fi
echo "animate output CLI: ok"
