#!/usr/bin/env bash
# A run writes all its outputs or none (issue 18): concurrent runs into one folder, an
# interrupted run, outputs whose place is wrong, non-regular input files.
. "$(dirname "$0")/cli_lib.sh"
small=(--set screen.width=128 --set screen.height=128 --set gp.count=2 --set renderer.count=1)
leftovers() { find "$1" \( -name '.*.??????' -o -name '*.tmp' \) 2>/dev/null | head -1; }

# Two runs into the same folder at once: both succeed, each with a complete set of its own,
# and no temporary is left.
"$bin" render --scene torus "${small[@]}" --out "$tmp/same" >"$tmp/a.log" 2>&1 &
a=$!
"$bin" render --scene sphere "${small[@]}" --out "$tmp/same" >"$tmp/b.log" 2>&1 &
b=$!
wait $a || fail "first concurrent run failed: $(cat "$tmp/a.log")"
wait $b || fail "second concurrent run failed: $(cat "$tmp/b.log")"
for f in frame.png regions.png config.json stats.json; do [ -s "$tmp/same/$f" ] || fail "no $f"; done
[ -z "$(leftovers "$tmp/same")" ] || fail "temporary left: $(leftovers "$tmp/same")"

# Interrupted runs leave no temporary files, whenever the signal comes.
for delay in 0.05 0.1 0.2 0.3; do
  "$bin" render --scene torus --out "$tmp/int" --timeline "$tmp/int/t.json" >/dev/null 2>&1 &
  pid=$!
  sleep "$delay"
  kill -INT $pid 2>/dev/null
  wait $pid
done
[ -z "$(leftovers "$tmp/int")" ] || fail "an interrupted run left $(leftovers "$tmp/int")"

# Outputs whose place is wrong are refused before anything is written.
expect_error "the folder $tmp/missing does not exist" render --scene two-triangles "${small[@]}" \
  --out "$tmp/tl" --timeline "$tmp/missing/t.json"
[ -e "$tmp/tl/frame.png" ] && fail "frame.png written although the timeline could not be"
[ -e "$tmp/tl/regions.png" ] && fail "regions.png written although the timeline could not be"
expect_error "frame.png: named twice" render --scene two-triangles "${small[@]}" --out "$tmp/tl" \
  --timeline "$tmp/tl/frame.png"
touch "$tmp/file"
expect_error "--out $tmp/file: is a file, expected an output folder" render --scene two-triangles \
  --out "$tmp/file"
mkdir -p "$tmp/dirs/frame.png"
expect_error "frame.png: is a folder, expected a file to write" render --scene two-triangles \
  "${small[@]}" --out "$tmp/dirs"
[ -e "$tmp/dirs/stats.json" ] && fail "stats.json written beside a frame that could not be"
# A name too long for a ".tmp" suffix is still written (the temporary's name is shorter).
long="$tmp/$(printf 'x%.0s' $(seq 1 250)).json"
"$bin" render --scene two-triangles "${small[@]}" --out "$tmp/long" --timeline "$long" >/dev/null \
  || fail "a 251-character timeline name was refused"

# A full disk: a run that cannot write everything leaves the previous run's outputs as they
# were and no temporary, and names the reason. A 36 KiB tmpfs in a private mount namespace
# holds the first run's files but not all of the second's (its regions.png or its 29 KB
# stats.json no longer fit), so writing file by file would leave a new frame beside an old
# stats.json (skipped where unprivileged namespaces are not allowed).
if unshare --user --map-root-user --mount true 2>/dev/null; then
  full=$(unshare --user --map-root-user --mount sh -c '
    bin="$1"; dir="$2"; shift 2
    mkdir -p "$dir/disk" && mount -t tmpfs -o size=36k tmpfs "$dir/disk" || exit 90
    "$bin" render --scene two-triangles "$@" --out "$dir/disk/run" >/dev/null 2>&1 || exit 91
    cp "$dir/disk/run/stats.json" "$dir/old-stats.json"; cp "$dir/disk/run/frame.png" "$dir/old-frame.png"
    "$bin" render --scene torus --set screen.width=128 --set screen.height=128 \
      --out "$dir/disk/run" 2>&1 && exit 92
    cmp -s "$dir/disk/run/stats.json" "$dir/old-stats.json" || exit 93
    cmp -s "$dir/disk/run/frame.png" "$dir/old-frame.png" || exit 94
    [ -z "$(find "$dir/disk" -name ".*.??????")" ] || exit 95
    exit 0' sh "$bin" "$tmp" "${small[@]}")
  status=$?
  [ $status -eq 0 ] || fail "full disk: step $status failed: $full"
  echo "$full" | grep -Eq "(regions.png|stats.json): cannot write \(No space left on device\)" \
    || fail "full disk said: $full"
else
  echo "output_cli: full-disk check skipped (no unprivileged mount namespace here)"
fi

# A mesh named "...obj" gets out/scene, not out/.. (run in a scratch folder).
mkdir -p "$tmp/cwd"
printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n' > "$tmp/cwd/...obj"
(cd "$tmp/cwd" && "$bin" render --scene ...obj "${small[@]}" >/dev/null) || fail "...obj failed"
[ -s "$tmp/cwd/out/scene/frame.png" ] || fail "...obj did not write out/scene/frame.png"

# A second run into a folder says it replaced the first's outputs.
"$bin" render --scene two-triangles "${small[@]}" --out "$tmp/again" >/dev/null || fail "first run"
"$bin" render --scene two-triangles "${small[@]}" --out "$tmp/again" | grep -q "replacing the previous run's" \
  || fail "a second run into one folder did not say it replaced the first's outputs"

# FIFOs, devices and folders as inputs are refused at once, not read.
mkfifo "$tmp/fifo.obj" "$tmp/fifo.json" "$tmp/fifo.pp5" "$tmp/fifo-config.json"
expect_error "$tmp: is a directory, expected a machine configuration" render --config "$tmp" --out "$tmp/f"
# (Each under `timeout`, so that a regression fails instead of hanging the suite.)
pp5sim="$bin"
bin=timeout
expect_error "fifo.obj: is a FIFO" 10 "$pp5sim" render --scene "$tmp/fifo.obj" --out "$tmp/f"
expect_error "fifo.json: is a FIFO" 10 "$pp5sim" render --scene "$tmp/fifo.json" --out "$tmp/f"
expect_error "fifo.pp5: is a FIFO" 10 "$pp5sim" render --firmware "$tmp/fifo.pp5" --out "$tmp/f"
expect_error "/dev/zero: is a character device" 10 "$pp5sim" asm /dev/zero
expect_error "fifo-config.json: is a FIFO" 10 "$pp5sim" render --config "$tmp/fifo-config.json" --out "$tmp/f"
bin="$pp5sim"
echo "output_cli: all checks passed"
