#!/usr/bin/env bash
# Output targets that are not regular files, and a run's files appearing together or not at
# all under concurrent runs and signals (sim/output/output_set.hpp).
. "$(dirname "$0")/cli_lib.sh"
bin=$(readlink -f "$bin")
small=(--set screen.width=128 --set screen.height=128 --set gp.count=2 --set renderer.count=1)
cd "$tmp" || fail "no scratch folder"

# A FIFO named as an output is written into, not replaced by a regular file.
mkfifo fifo
timeout 20 cat fifo > fifo.out &
reader=$!
timeout 20 "$bin" render --scene two-triangles "${small[@]}" --out r --timeline fifo >/dev/null \
  || fail "a timeline into a FIFO failed"
wait $reader
[ -p fifo ] || fail "the FIFO was replaced: $(ls -l fifo)"
grep -q traceEvents fifo.out || fail "the timeline did not come through the FIFO"

# A symbolic link stays a link; its target is written (and created, if missing).
echo old > target.json
ln -s target.json link.json
ln -s missing.json dangling.json
"$bin" render --scene two-triangles "${small[@]}" --out r --timeline link.json >/dev/null \
  || fail "a timeline through a link failed"
[ -L link.json ] || fail "the link was replaced: $(ls -l link.json)"
grep -q traceEvents target.json || fail "the link's target was not written"
"$bin" render --scene two-triangles "${small[@]}" --out r --timeline dangling.json >/dev/null \
  || fail "a timeline through a dangling link failed"
[ -L dangling.json ] && [ -s missing.json ] || fail "a dangling link's target was not created"
# The same for a trace, a sweep's CSV and the Slurm script.
"$bin" trace record --scene two-triangles "${small[@]}" --pixel 10,10 -o link.json >/dev/null \
  || fail "trace record through a link failed"
[ -L link.json ] && head -c 8 target.json | grep -q PP5TRACE || fail "trace record replaced the link"
"$bin" sweep --scene two-triangles "${small[@]}" --grid gp.count=1,2 --out sw >/dev/null 2>&1 \
  || fail "sweep failed"
ln -s sweep-target.csv sweep.csv
"$bin" sweep aggregate sw -o sweep.csv >/dev/null || fail "sweep aggregate through a link failed"
[ -L sweep.csv ] && grep -q gp.count sweep-target.csv || fail "sweep aggregate replaced the link"
ln -s submit-target.sh submit.sh
"$bin" sweep --scene two-triangles --grid gp.count=1,2 --out sl --slurm submit.sh >/dev/null \
  || fail "--slurm through a link failed"
[ -L submit.sh ] && grep -q sbatch submit-target.sh || fail "--slurm replaced the link"
# /dev/stdout into a pipe: /proc/self/fd/1 links to "pipe:[N]", no path; written in place.
"$bin" render --scene two-triangles "${small[@]}" --out r --timeline /dev/stdout | grep -q traceEvents \
  || fail "a timeline to /dev/stdout (a pipe) did not come through"
# A link loop is named, not followed forever.
ln -s loop loop
expect_error "loop: too many levels of symbolic links" render --scene two-triangles "${small[@]}" \
  --out r --timeline loop
# A file size limit (ulimit -f): an error naming the file, nothing left behind (SIGXFSZ ended
# the run with its folder made and empty).
out=$( (ulimit -f 1; "$bin" render --scene two-triangles "${small[@]}" --out fsize --timeline fsize.json 2>&1) ) \
  && fail "a run past the file size limit succeeded"
echo "$out" | grep -q "cannot write (File too large)" || fail "ulimit -f said: $out"
[ -e fsize ] || [ -e fsize.json ] && fail "a run past the file size limit left $(ls -d fsize*)"
# A socket cannot be written: refused, with nothing else written.
if python3 -c 'import socket,sys; socket.socket(socket.AF_UNIX).bind(sys.argv[1])' sock 2>/dev/null; then
  expect_error "sock: is a socket, expected a file, a FIFO or a device" render --scene two-triangles \
    "${small[@]}" --out sockrun --timeline sock
  [ -e sockrun/frame.png ] && fail "frame.png written although the timeline could not be"
fi
# A device node (made here, so that a regression cannot replace the system's /dev/null).
if mknod null c 1 3 2>/dev/null; then
  "$bin" render --scene two-triangles "${small[@]}" --out r --timeline null >/dev/null \
    || fail "a timeline into a device failed"
  [ -c null ] || fail "the device node was replaced: $(ls -l null)"
  if mknod full c 1 7 2>/dev/null; then
    rm -rf devfull
    expect_error "full: cannot write (No space left on device)" render --scene two-triangles \
      "${small[@]}" --out devfull --timeline full
    [ -e devfull/frame.png ] && fail "frame.png written although the timeline could not be"
    [ -c full ] || fail "the device node was replaced: $(ls -l full)"
  fi
else
  echo "output_targets_cli: device-node checks skipped (mknod needs root)"
fi

# Two runs into one folder, each pausing between its renames (the test hook
# PP5_TEST_COMMIT_PAUSE_MS), one slowly and one quickly, so that without a lock the quick one
# would overtake the slow one half-way: the folder ends with one run's complete set, never frame.png
# from one beside config.json from the other. The runs differ in scene and in gp.count, so
# that frame.png and config.json each tell whose they are.
"$bin" render --scene torus "${small[@]}" --out ref-a >/dev/null || fail "reference run a"
"$bin" render --scene sphere "${small[@]}" --set gp.count=3 --out ref-b >/dev/null || fail "reference run b"
for attempt in 1 2; do
  rm -rf same
  PP5_TEST_COMMIT_PAUSE_MS=1000 "$bin" render --scene torus "${small[@]}" --out same >/dev/null 2>&1 &
  a=$!
  # The second run starts once the first is moving its files into place.
  for _ in $(seq 200); do [ -e same/frame.png ] && break; sleep 0.02; done
  PP5_TEST_COMMIT_PAUSE_MS=50 "$bin" render --scene sphere "${small[@]}" --set gp.count=3 \
    --out same >/dev/null 2>&1 &
  b=$!
  wait $a || fail "concurrent run a failed"
  wait $b || fail "concurrent run b failed"
  if cmp -s same/frame.png ref-a/frame.png; then winner=ref-a; else winner=ref-b; fi
  for f in frame.png regions.png config.json; do
    cmp -s "same/$f" "$winner/$f" || fail "attempt $attempt: $f is not from the run that wrote frame.png ($winner)"
  done
done

# A signal while a run moves its files into place waits for the last one: the folder holds
# the whole set, and the process still ends by the signal.
for signal in INT TERM HUP; do
  rm -rf sig
  PP5_TEST_COMMIT_PAUSE_MS=400 "$bin" render --scene torus "${small[@]}" --out sig >/dev/null 2>&1 &
  pid=$!
  for _ in $(seq 200); do [ -e sig/frame.png ] && break; sleep 0.02; done
  [ -e sig/frame.png ] || fail "SIG$signal: the run never reached its commit"
  kill -"$signal" $pid
  wait $pid
  status=$?
  [ $status -gt 128 ] || fail "SIG$signal: the run did not end by the signal (status $status)"
  for f in frame.png regions.png config.json stats.json; do
    [ -s "sig/$f" ] || fail "SIG$signal during the commit: $f missing ($(ls sig))"
  done
  [ -z "$(find sig -name '.*.??????')" ] || fail "SIG$signal: a temporary was left"
done

# A signal before the commit leaves nothing: no file, no empty folder (nor its new parents).
for signal in INT TERM HUP; do
  for delay in 0.02 0.05 0.1 0.2; do
    rm -rf early
    "$bin" render --scene torus --out early/run >/dev/null 2>&1 &
    pid=$!
    sleep "$delay"
    kill -"$signal" $pid 2>/dev/null
    wait $pid
    if [ -e early ]; then
      # The run finished before the signal: then its set is whole.
      for f in frame.png regions.png config.json stats.json; do
        [ -s "early/run/$f" ] || fail "SIG$signal after ${delay}s left early/ without $f: $(find early)"
      done
    fi
  done
done

# A sweep never sends two runs into one folder.
expect_error "value '2' is given twice for 'gp.count'" sweep --scene two-triangles \
  --grid gp.count=1,2,2 --out dup --print-commands
# A regular file with other hard links is replaced through the rename like any regular file
# (decided: all or none matters more): the name given holds the new run, and every other name
# of the old file keeps the previous run's content, as after mv or sed -i.
"$bin" render --scene two-triangles "${small[@]}" --out hl >/dev/null 2>&1 || fail "render hl"
ln hl/stats.json kept.json
before=$(cksum < kept.json)
"$bin" render --scene crossing-quads "${small[@]}" --out hl >/dev/null 2>&1 || fail "render hl again"
[ "$(cksum < kept.json)" = "$before" ] || fail "the other hard link was written in place"
! cmp -s hl/stats.json kept.json \
  || fail "the named file does not hold the new run"
[ "$(stat -c %h kept.json)" = 1 ] && [ "$(stat -c %h hl/stats.json)" = 1 ] \
  || fail "link counts after the rename: $(stat -c %h kept.json hl/stats.json)"
echo "output_targets_cli: all checks passed"
